//! What a text data file may hold before its reader gives up, checked while
//! it streams: a binary file is refused at its first KiB, and neither a
//! line nor the whole set can grow past a stated size, so reading any
//! file, whatever its size, needs a bounded amount of memory.

use anyhow::{bail, Result};
use std::io::{self, Read};

/// The most samples one data set may hold. A million rows of
/// `Observation` are about 90 MB, and a fit's every evaluation visits each
/// of them: more is a table to subsample, not a set to fit.
pub const MAX_ROWS: usize = 1_000_000;
/// The longest line of a text data file; a sample's row is under 300 bytes.
pub const MAX_LINE_BYTES: usize = 64 * 1024;
/// How much of a file is looked at before anything is parsed.
pub const SNIFF_BYTES: usize = 1024;

/// Refuses a start of a file that is not text: a NUL byte, or bytes that
/// are not UTF-8 (a character cut by the end of `head` is text).
pub fn sniff(head: &[u8]) -> Result<()> {
    let head = &head[..head.len().min(SNIFF_BYTES)];
    if let Some(at) = head.iter().position(|&b| b == 0) {
        bail!("byte {at} is NUL: binary content, not a text data file (ALTA `.dat` or CSV)");
    }
    if let Err(e) = std::str::from_utf8(head) {
        if e.error_len().is_some() {
            bail!(
                "byte {} is not UTF-8 text: binary content, not a text data file (ALTA `.dat` or CSV)",
                e.valid_up_to()
            );
        }
    }
    Ok(())
}

/// The error of a set that grew past [`MAX_ROWS`].
pub fn too_many_rows() -> anyhow::Error {
    anyhow::anyhow!(
        "more than {MAX_ROWS} samples: beyond what one data set holds (the limit keeps reading and fitting within memory); subsample the file"
    )
}

/// What [`Guarded`] found; its message names the line, which a reader
/// reading ahead of its parser cannot know.
#[derive(Debug)]
struct Refused(String);

impl std::fmt::Display for Refused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Refused {}

/// A read error met at line `line`: [`Guarded`]'s as it is, any other
/// (text that is not UTF-8, a failing disk) with the line's number.
pub fn line_error(e: io::Error, line: usize) -> anyhow::Error {
    match e.get_ref().and_then(|r| r.downcast_ref::<Refused>()) {
        Some(r) => anyhow::anyhow!("{r}"),
        None => anyhow::anyhow!("line {line}: {e}"),
    }
}

/// A reader that fails, as an `InvalidData` error, at a NUL byte anywhere
/// or at a line longer than [`MAX_LINE_BYTES`].
pub struct Guarded<R> {
    inner: R,
    offset: u64,
    line: u64,
    line_bytes: usize,
}

impl<R: Read> Guarded<R> {
    pub fn new(inner: R) -> Self {
        Guarded {
            inner,
            offset: 0,
            line: 1,
            line_bytes: 0,
        }
    }
}

impl<R: Read> Read for Guarded<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        for &b in &buf[..n] {
            match b {
                0 => {
                    return Err(io::Error::new(
                        io::ErrorKind::InvalidData,
                        Refused(format!(
                            "line {}: byte {} is NUL: binary content, not a text data file",
                            self.line, self.offset
                        )),
                    ))
                }
                b'\n' => {
                    self.line += 1;
                    self.line_bytes = 0;
                }
                _ => {
                    self.line_bytes += 1;
                    if self.line_bytes > MAX_LINE_BYTES {
                        return Err(io::Error::new(
                            io::ErrorKind::InvalidData,
                            Refused(format!(
                                "line {}: longer than {} KiB: not a row of samples",
                                self.line,
                                MAX_LINE_BYTES / 1024
                            )),
                        ));
                    }
                }
            }
            self.offset += 1;
        }
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sniff_refuses_nul_and_non_utf8_but_not_a_cut_character() {
        assert!(sniff(b"#DIM 3 1\n").is_ok());
        assert!(sniff(&[0u8; 4096]).unwrap_err().to_string().contains("byte 0 is NUL"));
        assert!(sniff(b"#DIM\xff 3").unwrap_err().to_string().contains("byte 4 is not UTF-8"));
        // "θ" is two bytes; the head ends after the first.
        assert!(sniff(&"θ".as_bytes()[..1]).is_ok());
    }

    #[test]
    fn guarded_stops_at_nul_and_at_a_long_line() {
        let mut out = Vec::new();
        let e = Guarded::new(&b"a\nb\0"[..]).read_to_end(&mut out).unwrap_err();
        assert!(e.to_string().contains("line 2: byte 3 is NUL"), "{e}");
        let long = vec![b'1'; MAX_LINE_BYTES + 1];
        let e = Guarded::new(&long[..]).read_to_end(&mut out).unwrap_err();
        assert!(e.to_string().contains("line 1: longer than 64 KiB"), "{e}");
        let ok = format!("{}\n{}", "1".repeat(MAX_LINE_BYTES), "1".repeat(MAX_LINE_BYTES));
        assert!(Guarded::new(ok.as_bytes()).read_to_end(&mut out).is_ok());
    }
}
