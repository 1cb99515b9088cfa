//! Fuzzes the experiment-plan reader. Instance globs resolve against an empty directory and
//! cannot leave it, so a mutated pattern cannot walk the file system.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

fuzz_target!(|data: &[u8]| {
    static BASE: OnceLock<PathBuf> = OnceLock::new();
    let base = BASE.get_or_init(|| {
        let d = std::env::temp_dir().join(format!("cellseq-fuzz-plan-{}", std::process::id()));
        let _ = std::fs::create_dir_all(&d);
        d
    });
    // an absolute glob, or one climbing out of the base with `..`, would walk the machine's
    // file system (confining globs is the plan reader's job; see docs/bad-input.md): such
    // paths are defused, the rest of the plan is parsed as given
    let text = String::from_utf8_lossy(data)
        .replace("..", "._")
        .replace("\"/", "\"_")
        .replace("'/", "'_");
    let _ = cellseq_lab::plan::Plan::parse("fuzz.toml", &text, base);
});
