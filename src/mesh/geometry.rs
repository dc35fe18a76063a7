//! Normals and curvature.
use super::{MeshError, Surface, TriMesh};
use glam::DVec3;

/// Per-face second fundamental form in the face frame (u, v).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FaceCurvature {
    pub u: DVec3,
    pub v: DVec3,
    pub e: f64,
    pub f: f64,
    pub g: f64,
}

pub fn build_surface(_mesh: TriMesh, _axis: DVec3) -> Result<Surface, MeshError> {
    unimplemented!("skeleton")
}
