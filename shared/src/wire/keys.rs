//! Key matching at the width the sender chose: postcard-rpc shrinks keys
//! when they stay unambiguous, and a reply uses its request's width.

use postcard_rpc::header::VarKey;
use postcard_rpc::Key;

/// Whether the frame key `got` is `key` at the width the host chose.
pub fn key_is(key: Key, got: &VarKey) -> bool {
    let mut k = VarKey::Key8(key);
    k.shrink_to(got.kind());
    k == *got
}
