#![no_main]
//! Fuzzes the bench-file loader (`vrao bench --replot`, `vrao budget --fit`, the
//! governor's frontier): any text is refused naming the file, or loads with every
//! record in range.

use libfuzzer_sys::fuzz_target;
use vrao::formats::bench_file::BenchFile;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(file) = BenchFile::from_json(&text, std::path::Path::new("fuzz.json")) {
        assert!(file.records.iter().all(|r| r.radius_m > 0.0 && r.occlusion_ms_per_eye >= 0.0));
    }
});
