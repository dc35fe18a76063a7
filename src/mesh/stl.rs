//! STL bytes → triangle soup (binary or ASCII).
use super::{MeshError, TriMesh};

/// Reads binary or ASCII STL into an unwelded soup (three fresh corners per triangle).
pub fn read(_bytes: &[u8], _max_triangles: usize) -> Result<TriMesh, MeshError> {
    unimplemented!("skeleton")
}
