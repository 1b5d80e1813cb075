//! Fuzz the OFF reader: any input must give Ok or an error, never a panic; a soup that
//! reads must also build a mesh (or fail) and validate without panicking.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(soup) = fires_recon::io::read_off(std::io::Cursor::new(data)) {
        if let Ok(mesh) = soup.to_mesh() {
            let _ = mesh.validate();
        }
        // The repairing build must succeed on any in-range soup and give a valid mesh.
        if let Ok((mesh, _)) = soup.to_mesh_repaired() {
            assert!(mesh.validate().is_ok());
        }
    }
});
