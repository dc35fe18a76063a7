//! STL bytes → triangle soup (binary or ASCII).
//!
//! Binary is decided by size: a file of exactly `84 + 50·n` bytes, where `n` is the count in
//! bytes 80..84, is binary even when its header starts with `solid` (many CAD exporters write
//! such headers). Otherwise a file starting with `solid` is parsed as ASCII, and anything else
//! is a binary file whose size does not match: reported as truncated.

use super::{MeshError, TriMesh};
use glam::DVec3;

const HEADER: usize = 80;
const RECORD: usize = 50;

/// Reads binary or ASCII STL into an unwelded soup: three fresh corners per triangle, in file
/// order. Refuses more than `max_triangles` triangles before allocating for them.
pub fn read(bytes: &[u8], max_triangles: usize) -> Result<TriMesh, MeshError> {
    if bytes.iter().all(|b| b.is_ascii_whitespace()) {
        return Err(MeshError::Empty);
    }
    // The count a binary file declares, if it is long enough to declare one.
    let declared = bytes.get(HEADER..HEADER + 4).map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")) as u64);
    if let Some(n) = declared {
        if (HEADER + 4) as u64 + RECORD as u64 * n == bytes.len() as u64 {
            return read_binary(bytes, n, max_triangles);
        }
    }
    if looks_ascii(bytes) {
        return read_ascii(bytes, max_triangles);
    }
    let n = declared.unwrap_or(0);
    Err(MeshError::Truncated {
        triangles: n,
        expected_bytes: (HEADER + 4) as u64 + RECORD as u64 * n,
        actual_bytes: bytes.len() as u64,
    })
}

/// Starts with `solid` and is text: a binary file whose header starts with `solid` has control
/// bytes in its counts and floats, so a truncated one is still reported as a truncated binary.
fn looks_ascii(bytes: &[u8]) -> bool {
    let start = bytes.iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(0);
    let is_text = bytes.iter().all(|&b| b >= 0x20 && b != 0x7f || matches!(b, b'\t' | b'\n' | b'\r' | 0x0c));
    bytes[start..].len() >= 5 && bytes[start..start + 5].eq_ignore_ascii_case(b"solid") && is_text
}

fn read_binary(bytes: &[u8], n: u64, max_triangles: usize) -> Result<TriMesh, MeshError> {
    if n > max_triangles as u64 {
        return Err(MeshError::TooManyTriangles { count: n, cap: max_triangles });
    }
    if n == 0 {
        return Err(MeshError::NoTriangles);
    }
    let n = n as usize;
    let mut positions = Vec::with_capacity(3 * n);
    for (t, record) in bytes[HEADER + 4..].chunks_exact(RECORD).enumerate() {
        // Bytes 0..12 hold the facet normal: ignored, the winding defines orientation.
        for c in 0..3 {
            let o = 12 + 12 * c;
            let f = |k: usize| f32::from_le_bytes(record[o + 4 * k..o + 4 * k + 4].try_into().expect("4 bytes"));
            let p = DVec3::new(f(0) as f64, f(1) as f64, f(2) as f64);
            if !p.is_finite() {
                return Err(MeshError::NonFinite { triangle: t });
            }
            positions.push(p);
        }
    }
    Ok(soup(positions))
}

fn read_ascii(bytes: &[u8], max_triangles: usize) -> Result<TriMesh, MeshError> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = bytes[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count() + 1;
        MeshError::AsciiSyntax { line, message: "the file is neither binary STL nor ASCII text".into() }
    })?;
    let mut positions: Vec<DVec3> = Vec::new();
    let mut corners_in_facet = 0usize;
    let mut in_loop = false;
    let mut seen_endsolid = false;
    let err = |line: usize, message: String| MeshError::AsciiSyntax { line, message };
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let mut words = raw.split_ascii_whitespace();
        let Some(keyword) = words.next() else { continue };
        match keyword.to_ascii_lowercase().as_str() {
            "solid" => {}
            "endsolid" => seen_endsolid = true,
            "facet" => {
                if in_loop {
                    return Err(err(line, "`facet` inside an open `outer loop`".into()));
                }
                if positions.len() / 3 >= max_triangles {
                    return Err(MeshError::TooManyTriangles {
                        count: positions.len() as u64 / 3 + 1,
                        cap: max_triangles,
                    });
                }
            }
            "outer" => {
                if in_loop {
                    return Err(err(line, "nested `outer loop`".into()));
                }
                in_loop = true;
                corners_in_facet = 0;
            }
            "vertex" => {
                if !in_loop {
                    return Err(err(line, "`vertex` outside `outer loop`".into()));
                }
                let mut c = [0.0f64; 3];
                for v in &mut c {
                    let w = words.next().ok_or_else(|| err(line, "a vertex needs 3 coordinates".into()))?;
                    *v = w.parse::<f64>().map_err(|_| err(line, format!("`{w}` is not a number")))?;
                }
                let p = DVec3::from_array(c);
                if !p.is_finite() {
                    return Err(MeshError::NonFinite { triangle: positions.len() / 3 });
                }
                corners_in_facet += 1;
                if corners_in_facet > 3 {
                    return Err(err(line, "a facet has more than 3 vertices".into()));
                }
                positions.push(p);
            }
            "endloop" => {
                if !in_loop || corners_in_facet != 3 {
                    return Err(err(line, format!("a facet has {corners_in_facet} vertices, expected 3")));
                }
                in_loop = false;
            }
            "endfacet" => {
                if in_loop {
                    return Err(err(line, "`endfacet` before `endloop`".into()));
                }
            }
            other => {
                let shown: String = other.chars().take(24).collect();
                return Err(err(line, format!("unexpected `{shown}`")));
            }
        }
    }
    if in_loop {
        return Err(err(text.lines().count(), "the file ends inside a facet (truncated?)".into()));
    }
    if positions.is_empty() {
        return Err(MeshError::NoTriangles);
    }
    if !seen_endsolid {
        return Err(err(text.lines().count(), "missing `endsolid` (truncated?)".into()));
    }
    Ok(soup(positions))
}

fn soup(positions: Vec<DVec3>) -> TriMesh {
    let n = positions.len() as u32 / 3;
    TriMesh { positions, triangles: (0..n).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect() }
}

/// Writes a binary STL (f32, little-endian); the facet normal is computed from the winding.
/// The header is truncated or zero-padded to 80 bytes and never starts with `solid`.
pub fn write_binary(mesh: &TriMesh, header: &str) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER + 4 + RECORD * mesh.triangles.len());
    let mut h = [0u8; HEADER];
    let text = header.as_bytes();
    let text = if text.len() >= 5 && text[..5].eq_ignore_ascii_case(b"solid") { &text[5..] } else { text };
    let n = text.len().min(HEADER);
    h[..n].copy_from_slice(&text[..n]);
    out.extend_from_slice(&h);
    out.extend_from_slice(&(mesh.triangles.len() as u32).to_le_bytes());
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let normal = (b - a).cross(c - a).normalize_or_zero();
        for v in [normal, a, b, c] {
            for x in v.to_array() {
                out.extend_from_slice(&(x as f32).to_le_bytes());
            }
        }
        out.extend_from_slice(&[0, 0]);
    }
    out
}

/// Writes an ASCII STL (`solid name` … `endsolid name`); numbers are f32 printed with `{:e}`,
/// which round-trips exactly.
pub fn write_ascii(mesh: &TriMesh, name: &str) -> String {
    use std::fmt::Write;
    let mut s = String::with_capacity(64 + 260 * mesh.triangles.len());
    let f = |v: DVec3| format!("{:e} {:e} {:e}", v.x as f32, v.y as f32, v.z as f32);
    let _ = writeln!(s, "solid {name}");
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let _ = writeln!(s, "  facet normal {}", f((b - a).cross(c - a).normalize_or_zero()));
        s.push_str("    outer loop\n");
        for p in [a, b, c] {
            let _ = writeln!(s, "      vertex {}", f(p));
        }
        s.push_str("    endloop\n  endfacet\n");
    }
    let _ = writeln!(s, "endsolid {name}");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> TriMesh {
        TriMesh {
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    #[test]
    fn binary_round_trip() {
        let bytes = write_binary(&square(), "test part");
        assert_eq!(bytes.len(), 84 + 2 * 50);
        let soup = read(&bytes, 10).unwrap();
        assert_eq!(soup.triangles.len(), 2);
        assert_eq!(soup.positions[2], DVec3::new(1.0, 1.0, 0.0));
    }

    #[test]
    fn binary_with_solid_header_is_binary() {
        let mut bytes = write_binary(&square(), "x");
        bytes[..12].copy_from_slice(b"solid binary");
        let soup = read(&bytes, 10).unwrap();
        assert_eq!(soup.triangles.len(), 2);
    }

    #[test]
    fn ascii_parses() {
        let text = "solid s\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid s\n";
        let soup = read(text.as_bytes(), 10).unwrap();
        assert_eq!(soup.positions, vec![DVec3::ZERO, DVec3::X, DVec3::Y]);
    }

    #[test]
    fn faults_are_named() {
        assert_eq!(read(b"", 10), Err(MeshError::Empty));
        assert_eq!(read(b"  \n", 10), Err(MeshError::Empty));
        let mut bytes = write_binary(&square(), "x");
        bytes.truncate(bytes.len() - 7);
        assert!(matches!(read(&bytes, 10), Err(MeshError::Truncated { triangles: 2, actual_bytes: 177, .. })));
        // Regression (issue 2, found by the browser tests): a truncated binary whose header
        // starts with `solid` is a truncated binary, not bad ASCII.
        bytes[..5].copy_from_slice(b"solid");
        assert!(matches!(read(&bytes, 10), Err(MeshError::Truncated { triangles: 2, .. })));
        let garbled = "solid s\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 zero\n";
        assert!(matches!(read(garbled.as_bytes(), 10), Err(MeshError::AsciiSyntax { line: 4, .. })));
        let nan = "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex NaN 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid\n";
        assert_eq!(read(nan.as_bytes(), 10), Err(MeshError::NonFinite { triangle: 0 }));
        let bytes = write_binary(&square(), "x");
        assert_eq!(read(&bytes, 1), Err(MeshError::TooManyTriangles { count: 2, cap: 1 }));
    }
}
