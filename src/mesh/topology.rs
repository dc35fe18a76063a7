//! Manifoldness, orientation, components, boundary loops.
use super::{MeshError, MeshReport, TriMesh};

pub struct Topology {
    pub mesh: TriMesh,
}

pub fn euler_characteristic(_vertices: usize, _triangles: &[[u32; 3]]) -> i64 {
    unimplemented!("skeleton")
}
pub fn analyse(_mesh: &TriMesh) -> Result<Topology, MeshError> {
    unimplemented!("skeleton")
}
pub fn report(_mesh: &TriMesh, _topo: &Topology) -> MeshReport {
    unimplemented!("skeleton")
}
pub fn largest_component(_topo: &Topology) -> (TriMesh, usize) {
    unimplemented!("skeleton")
}
