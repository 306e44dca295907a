//! Writes the fuzz targets' seed corpus (`fuzz/seeds/TARGET/NAME`)
//! from `gonio_frames::fuzz::seeds`: run it again when a message type changes.

use std::path::Path;

fn main() -> std::io::Result<()> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/seeds");
    let mut n = 0;
    for (target, name, bytes) in gonio_frames::fuzz::seeds() {
        let dir = root.join(target);
        std::fs::create_dir_all(&dir)?;
        std::fs::write(dir.join(name), bytes)?;
        n += 1;
    }
    eprintln!("{n} seeds written to {}", root.display());
    Ok(())
}
