//! Every committed seed of the fuzz targets (fuzz/seeds) through its
//! target on stable Rust, and the seeds up to date with the message types:
//! what `cargo fuzz` starts from is checked on every test run, and so is every
//! input a fuzzer once crashed on (`regression-*`, kept as seeds).

use std::path::Path;

#[test]
fn every_seed_passes_its_target_and_the_corpus_is_current() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/seeds");
    let mut ran = 0;
    for entry in std::fs::read_dir(&root).expect("fuzz/seeds") {
        let dir = entry.unwrap().path();
        let name = dir.file_name().unwrap().to_str().unwrap().to_string();
        let target = gonio_frames::fuzz::target(&name).unwrap_or_else(|| panic!("seeds for an unknown target {name}"));
        for seed in std::fs::read_dir(&dir).unwrap() {
            target(&std::fs::read(seed.unwrap().path()).unwrap());
            ran += 1;
        }
    }
    let want = gonio_frames::fuzz::seeds();
    // The generated seeds, and the inputs the fuzzers once crashed on (`regression-*`).
    assert!(
        ran >= want.len(),
        "run `cargo run -p gonio-frames --bin fuzz-seeds` to refresh the corpus"
    );
    for (target, name, bytes) in want {
        let path = root.join(target).join(name);
        assert!(
            std::fs::read(&path).ok() == Some(bytes),
            "{} is stale: run `cargo run -p gonio-frames --bin fuzz-seeds`",
            path.display()
        );
    }
}
