//! Machinable top surface of a closed solid.
use super::{MeshError, TriMesh};
use glam::DVec3;

pub fn top_surface(_mesh: &TriMesh, _axis: DVec3, _wall_angle_deg: f64) -> Result<TriMesh, MeshError> {
    unimplemented!("skeleton")
}
