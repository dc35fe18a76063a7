//! The machinable top surface of a closed solid (DESIGN.md "mesh").
//!
//! A closed solid has no boundary to spiral in from. What a 3-axis ball-end finishing pass sees
//! from the tool axis is the set of faces whose outward normal is within the wall angle of the
//! axis; steep walls of bosses and pockets drop out and leave holes behind. The caller keeps the
//! largest component of the result.

use super::{weld, MeshError, TriMesh};
use glam::DVec3;

/// Faces of an outward-oriented closed mesh whose normal is within `wall_angle_deg` of `axis`.
pub fn top_surface(mesh: &TriMesh, axis: DVec3, wall_angle_deg: f64) -> Result<TriMesh, MeshError> {
    let axis = axis.normalize();
    let cos_wall = crate::num::cos(wall_angle_deg.to_radians());
    let faces: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .filter(|t| {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
            (b - a).cross(c - a).normalize_or_zero().dot(axis) >= cos_wall
        })
        .copied()
        .collect();
    if faces.is_empty() {
        return Err(MeshError::NothingFacesTool { axis: axis.to_array(), wall_angle_deg });
    }
    Ok(weld::compact(&mesh.positions, &faces))
}
