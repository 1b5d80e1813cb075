//! Tagging a curve sharp (FIRES thesis §5.4 uses per-curve sharpness for creases): sets the sharpness of
//! every polyline made of one stroke, by a pen mode or a journal step.

use super::ToolError;
use crate::network::mesh::Network;
use crate::network::{PolylineId, Transaction};

/// Sets the sharpness (0 smooth .. 1 sharp) of every polyline of stroke `stroke`; returns how many.
pub fn tag_sharp(
    net: &mut Network,
    stroke: u32,
    sharpness: f64,
) -> Result<(usize, Transaction), ToolError> {
    if !(0.0..=1.0).contains(&sharpness) {
        return Err(ToolError::BadCurve(format!(
            "sharpness {sharpness} is outside 0..1"
        )));
    }
    let ids: Vec<PolylineId> = net
        .polylines()
        .filter(|(_, p)| p.attrs.stroke == Some(stroke))
        .map(|(id, _)| id)
        .collect();
    if ids.is_empty() {
        return Err(ToolError::NoSuchStroke { stroke });
    }
    net.transact(|net| {
        for &id in &ids {
            if let Some(mut p) = net.polyline(id).cloned() {
                p.attrs.sharpness = sharpness;
                net.set_polyline(id, Some(p));
            }
        }
        Ok(ids.len())
    })
}
