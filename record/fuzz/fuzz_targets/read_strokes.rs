//! Arbitrary bytes into the strokes-file reader (`strokes.json`, docs/strokes.md) and the report reader
//! (`report.json`, docs/report.md): the first byte picks which. Any input must give `Ok` or a typed error, never a
//! panic; a strokes file that reads must write and read back to the same value.
#![no_main]

use fires_record::{Report, StrokesFile};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&which, bytes)) = data.split_first() else {
        return;
    };
    if which % 2 == 0 {
        if let Ok(file) = StrokesFile::from_json(bytes) {
            let text = serde_json::to_vec(&file).expect("a read strokes file serialises");
            let again = StrokesFile::from_json(&text).expect("a written strokes file reads");
            assert_eq!(again.strokes.len(), file.strokes.len());
        }
    } else {
        let _ = Report::from_json(bytes);
    }
});
