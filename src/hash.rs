//! Hash maps keyed by vertex indices, with a fixed multiplicative hash (FxHash's). SipHash's
//! resistance to chosen keys buys nothing on a mesh, and it was most of the cost of the rim
//! refinement's edge maps (the 40k panel's coplanar flips took 14 ms with it). Fixed, so the maps
//! behave the same on every run and machine.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A map from directed edges (vertex pairs) to `V`.
pub(crate) type EdgeMap<V> = HashMap<(u32, u32), V, BuildHasherDefault<IndexHasher>>;

/// An empty [`EdgeMap`] with room for `n` edges.
pub(crate) fn edge_map<V>(n: usize) -> EdgeMap<V> {
    HashMap::with_capacity_and_hasher(n, Default::default())
}

/// FxHash: each word is mixed in by a rotate, xor and multiply.
#[derive(Default, Clone, Copy)]
pub(crate) struct IndexHasher(u64);

const SEED: u64 = 0x51_7c_c1_b7_27_22_0a_95;

impl Hasher for IndexHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }

    fn write_u32(&mut self, x: u32) {
        self.write_u64(x as u64);
    }

    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(SEED);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_edge_map_finds_every_edge_and_only_those() {
        let mut m = edge_map(100);
        for a in 0..100u32 {
            m.insert((a, (a * 7 + 3) % 100), a);
        }
        for a in 0..100u32 {
            assert_eq!(m.get(&(a, (a * 7 + 3) % 100)), Some(&a));
            assert_eq!(m.contains_key(&((a * 7 + 3) % 100, a)), (a * 49 + 24) % 100 == a);
        }
    }
}
