//! Analytic test surfaces (one deterministic generator for every test, benchmark and sample).
// Placeholder until the generator lands from branch `fixtures` (replaced at merge).
pub const NAMES: &[&str] = &[];
pub fn by_name(_name: &str) -> Option<crate::mesh::TriMesh> {
    None
}
