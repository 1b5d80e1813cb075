//! Reads a mesh file with the repairing reader, prints what was repaired and the mesh's
//! topology (`fires mesh info` prints the same JSON), and optionally writes the repaired
//! mesh.
//!
//! ```text
//! cargo run -p fires-recon --example mesh_repair -- MESH [OUT.off|.obj|.ply|.stl]
//! ```

use fires_recon::io::{read_mesh_file_repaired, write_mesh_file, PolygonSoup};
use fires_recon::mesh::mesh_info;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(input) = args.first() else {
        eprintln!("usage: mesh_repair MESH [OUT]");
        std::process::exit(2);
    };
    let (mesh, repairs) = read_mesh_file_repaired(input)?;
    let summary = repairs.summary();
    eprintln!(
        "{input}: {}",
        if summary.is_empty() {
            "nothing to repair"
        } else {
            &summary
        }
    );
    println!("{}", serde_json::to_string(&mesh_info(&mesh, &repairs))?);
    if let Some(out) = args.get(1) {
        write_mesh_file(out, &PolygonSoup::from_mesh(&mesh))?;
    }
    Ok(())
}
