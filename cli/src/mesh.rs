//! `fires mesh info FILE`: counts, topology and read repairs of a mesh file, as one JSON
//! line.

use std::path::PathBuf;

use anyhow::Context;
use fires_recon::io::mesh_file_info;

/// Arguments of `fires mesh`.
#[derive(Debug, clap::Args)]
pub struct MeshArgs {
    #[command(subcommand)]
    what: MeshKind,
}

#[derive(Debug, clap::Subcommand)]
enum MeshKind {
    /// Vertex/edge/face counts, face degrees, boundary loops, components, Euler
    /// characteristic, genus, manifoldness, orientability and what reading repaired.
    Info {
        /// Mesh file (OBJ, OFF, PLY, STL).
        file: PathBuf,
    },
}

/// Runs the subcommand and prints its JSON line.
pub fn run(args: &MeshArgs) -> anyhow::Result<()> {
    match &args.what {
        MeshKind::Info { file } => {
            let info =
                mesh_file_info(file).with_context(|| format!("reading {}", file.display()))?;
            println!("{}", serde_json::to_string(&info)?);
        }
    }
    Ok(())
}
