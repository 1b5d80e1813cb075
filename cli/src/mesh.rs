//! `fires mesh info FILE`: counts, topology and read repairs of a mesh file, as one JSON
//! line.

use std::path::PathBuf;

use anyhow::Context;
use fires_recon::io::{mesh_file_info, read_mesh_file_repaired};

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
    /// A mesh against a simulated recording's true object: the surface figures of report.json
    /// (docs/report.md, "Surface") as one JSON line; for surfaces made elsewhere (baselines, other tools).
    Compare {
        /// Mesh file (OBJ, OFF, PLY, STL), metres, in the recording's world frame.
        file: PathBuf,
        /// The simulated recording.
        #[arg(long)]
        truth: PathBuf,
        /// Name written as the figures' `method`.
        #[arg(long, default_value = "mesh")]
        method: String,
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
        MeshKind::Compare {
            file,
            truth,
            method,
        } => {
            let (mesh, _) = read_mesh_file_repaired(file)
                .with_context(|| format!("reading {}", file.display()))?;
            let reader = fires_record::RecordingReader::open(truth)
                .with_context(|| format!("cannot open recording {}", truth.display()))?;
            let object = crate::pipeline::true_object(&reader)?.ok_or_else(|| {
                anyhow::anyhow!(
                    "{} has no true object (truth/world.json target)",
                    truth.display()
                )
            })?;
            let surface = fires_recon::surface::ControlMesh {
                mesh,
                ..Default::default()
            };
            let mut report =
                crate::pipeline::surface_report(&surface, crate::recon::Method::V2, &object)?;
            report.method = method.clone();
            println!("{}", serde_json::to_string(&report)?);
        }
    }
    Ok(())
}
