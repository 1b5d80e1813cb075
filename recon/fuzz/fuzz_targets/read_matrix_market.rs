//! Fuzz the Matrix Market reader and the sparse assembly of what it returns.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(m) = fires_recon::io::read_matrix_market(std::io::Cursor::new(data)) {
        let _ = m.lower_triangle();
    }
});
