//! Welding of coincident corners.
use super::{MeshError, TriMesh};

pub struct Welded {
    pub mesh: TriMesh,
    pub degenerate_dropped: usize,
    pub duplicates_dropped: usize,
}

pub fn weld(_mesh: &TriMesh, _tolerance_rel: f64) -> Result<Welded, MeshError> {
    unimplemented!("skeleton")
}
