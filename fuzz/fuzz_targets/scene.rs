//! The scene parser: any bytes give a scene or an `InputError`, never a panic.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    // Files the scene references resolve in a directory that does not exist; absolute paths
    // (which could name /dev/zero) are left out.
    if text.contains("\"/") {
        return;
    }
    let _ = viewcloth::scene::load_str(text, Path::new("fuzz.json"), Path::new("/nonexistent-viewcloth-fuzz"), "fuzz");
});
