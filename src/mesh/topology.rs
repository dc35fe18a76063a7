//! Topology of a welded mesh: manifold edges, pinch vertices, orientation, components, boundary
//! loops, Euler characteristic and genus.
//!
//! Preconditions: no degenerate face (see [`super::weld`]). Everything is sort-based, O(n log n),
//! and deterministic: components are numbered by their lowest face, loops start at their lowest
//! vertex.

use super::{weld, MeshError, MeshReport, TriMesh};
use glam::DVec3;

const NONE: u32 = u32::MAX;

/// One connected component (faces connected through shared edges).
#[derive(Clone, Debug, PartialEq)]
pub struct ComponentInfo {
    pub faces: usize,
    pub vertices: usize,
    pub edges: usize,
    pub area: f64,
    /// Indices into [`Topology::loops`]: the outer loop (longest) first, then holes by length.
    pub loops: Vec<usize>,
}

impl ComponentInfo {
    pub fn euler_characteristic(&self) -> i64 {
        self.vertices as i64 - self.edges as i64 + self.faces as i64
    }
    pub fn genus(&self) -> i64 {
        (2 - self.loops.len() as i64 - self.euler_characteristic()) / 2
    }
    pub fn closed(&self) -> bool {
        self.loops.is_empty()
    }
}

/// The analysed mesh: pinch vertices split, faces consistently oriented (closed components
/// outward, open components with their mean normal towards the tool axis).
#[derive(Clone, Debug)]
pub struct Topology {
    pub mesh: TriMesh,
    pub face_component: Vec<u32>,
    pub components: Vec<ComponentInfo>,
    /// Boundary loops as vertex cycles, each with the surface on its left.
    pub loops: Vec<Vec<u32>>,
    pub edges: usize,
    pub faces_reoriented: usize,
    pub pinch_vertices_split: usize,
}

/// A component cut out as a mesh of its own, with its loops (outer first).
#[derive(Clone, Debug)]
pub struct Component {
    pub mesh: TriMesh,
    pub loops: Vec<Vec<u32>>,
}

/// `V − E + F` of an indexed mesh.
pub fn euler_characteristic(vertices: usize, triangles: &[[u32; 3]]) -> i64 {
    let mut edges: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
        .collect();
    crate::par::sort_unstable(&mut edges);
    edges.dedup();
    vertices as i64 - edges.len() as i64 + triangles.len() as i64
}

/// Analyses a welded mesh; `tool_axis` orients open components.
pub fn analyse(mesh: &TriMesh, tool_axis: DVec3) -> Result<Topology, MeshError> {
    let input = &mesh.triangles;
    let nf = input.len();
    let (neighbour, edges) = face_neighbours(mesh)?;
    let (mut triangles, mut positions, pinch_vertices_split) = split_pinches(mesh, &neighbour);

    // Orientation and components by breadth-first search over shared edges.
    let mut component = vec![NONE; nf];
    let mut flip = vec![false; nf];
    let mut n_components = 0u32;
    let mut queue = std::collections::VecDeque::new();
    for seed in 0..nf {
        if component[seed] != NONE {
            continue;
        }
        component[seed] = n_components;
        queue.push_back(seed);
        while let Some(f) = queue.pop_front() {
            for k in 0..3 {
                let g = neighbour[3 * f + k];
                if g == NONE {
                    continue;
                }
                let g = g as usize;
                let (a, b) = (input[f][k], input[f][(k + 1) % 3]);
                // Consistent neighbours traverse the shared edge in opposite directions.
                let same_direction = (0..3).any(|m| input[g][m] == a && input[g][(m + 1) % 3] == b);
                let want = flip[f] ^ same_direction;
                if component[g] == NONE {
                    component[g] = n_components;
                    flip[g] = want;
                    queue.push_back(g);
                } else if flip[g] != want {
                    return Err(MeshError::NonOrientable { a, b });
                }
            }
        }
        n_components += 1;
    }
    // Global orientation per component: closed → outward, open → towards the tool.
    let nc = n_components as usize;
    let mut volume = vec![0.0; nc];
    let mut towards_tool = vec![0.0; nc];
    let mut area = vec![0.0; nc];
    let mut has_boundary = vec![false; nc];
    for (f, t) in triangles.iter().enumerate() {
        let c = component[f] as usize;
        let [a, mut b, mut p] = t.map(|v| positions[v as usize]);
        if flip[f] {
            std::mem::swap(&mut b, &mut p);
        }
        let n2 = (b - a).cross(p - a);
        volume[c] += a.dot(b.cross(p));
        towards_tool[c] += n2.dot(tool_axis);
        area[c] += 0.5 * n2.length();
        has_boundary[c] |= (0..3).any(|k| neighbour[3 * f + k] == NONE);
    }
    let flipped: Vec<bool> = (0..nf)
        .map(|f| {
            let c = component[f] as usize;
            let keep = if has_boundary[c] { towards_tool[c] >= 0.0 } else { volume[c] >= 0.0 };
            flip[f] == keep
        })
        .collect();
    let loops = boundary_loops(&triangles, &neighbour, &flipped, positions.len());
    for (t, &f) in triangles.iter_mut().zip(&flipped) {
        if f {
            t.swap(1, 2);
        }
    }
    let faces_reoriented = flipped.iter().filter(|&&f| f).count();
    let mut components: Vec<ComponentInfo> =
        (0..nc).map(|c| ComponentInfo { faces: 0, vertices: 0, edges: 0, area: area[c], loops: Vec::new() }).collect();
    let mut vertex_component = vec![NONE; positions.len()];
    for (f, t) in triangles.iter().enumerate() {
        let c = component[f];
        components[c as usize].faces += 1;
        for &v in t {
            vertex_component[v as usize] = c;
        }
        for k in 0..3 {
            // Each edge once: from the lower-indexed face, or the only face.
            let g = neighbour[3 * f + k];
            if g == NONE || (g as usize) > f {
                components[c as usize].edges += 1;
            }
        }
    }
    for &c in &vertex_component {
        if c != NONE {
            components[c as usize].vertices += 1;
        }
    }
    let lengths: Vec<f64> = loops.iter().map(|l| loop_length(&positions, l)).collect();
    for (i, l) in loops.iter().enumerate() {
        components[vertex_component[l[0] as usize] as usize].loops.push(i);
    }
    for c in &mut components {
        // Longest first: the outer loop Γ0 leads, holes follow by decreasing length.
        c.loops.sort_by(|&a, &b| lengths[b].total_cmp(&lengths[a]).then(a.cmp(&b)));
    }
    positions.shrink_to_fit();
    triangles.shrink_to_fit();
    Ok(Topology {
        mesh: TriMesh { positions, triangles },
        face_component: component,
        components,
        loops,
        edges,
        faces_reoriented,
        pinch_vertices_split,
    })
}

/// For every face corner `k`, the face across edge `(t[k], t[k+1])`, or `NONE`; and the edge count.
fn face_neighbours(mesh: &TriMesh) -> Result<(Vec<u32>, usize), MeshError> {
    let mut half: Vec<(u32, u32, u32)> = Vec::with_capacity(3 * mesh.triangles.len());
    for (f, t) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            half.push((a.min(b), a.max(b), (3 * f + k) as u32));
        }
    }
    crate::par::sort_unstable(&mut half);
    let mut neighbour = vec![NONE; 3 * mesh.triangles.len()];
    let mut edges = 0;
    let mut i = 0;
    while i < half.len() {
        let mut j = i + 1;
        while j < half.len() && (half[j].0, half[j].1) == (half[i].0, half[i].1) {
            j += 1;
        }
        match j - i {
            1 => {}
            2 => {
                let (x, y) = (half[i].2, half[i + 1].2);
                neighbour[x as usize] = y / 3;
                neighbour[y as usize] = x / 3;
            }
            faces => {
                let (a, b) = (half[i].0, half[i].1);
                return Err(MeshError::NonManifoldEdge {
                    a,
                    b,
                    pa: mesh.positions[a as usize].to_array(),
                    pb: mesh.positions[b as usize].to_array(),
                    faces,
                });
            }
        }
        edges += 1;
        i = j;
    }
    Ok((neighbour, edges))
}

/// Faces around each vertex in CSR form: the faces of vertex v are
/// `faces[start[v]..start[v + 1]]`, in increasing order.
pub fn vertex_faces(vertices: usize, triangles: &[[u32; 3]]) -> (Vec<u32>, Vec<u32>) {
    let mut start = vec![0u32; vertices + 1];
    for t in triangles {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for v in 0..vertices {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut faces = vec![0u32; start[vertices] as usize];
    for (f, t) in triangles.iter().enumerate() {
        for &v in t {
            faces[fill[v as usize] as usize] = f as u32;
            fill[v as usize] += 1;
        }
    }
    (start, faces)
}

/// Splits every vertex whose faces form several fans (a "pinch", e.g. two holes touching at a
/// corner) into one vertex per fan, so boundary loops are simple and well defined.
fn split_pinches(mesh: &TriMesh, neighbour: &[u32]) -> (Vec<[u32; 3]>, Vec<DVec3>, usize) {
    let nv = mesh.positions.len();
    let mut triangles = mesh.triangles.clone();
    let mut positions = mesh.positions.clone();
    let (start, incident) = vertex_faces(nv, &mesh.triangles);
    let mut split = 0;
    let mut fan: Vec<u32> = Vec::new();
    for v in 0..nv {
        let faces = &incident[start[v] as usize..start[v + 1] as usize];
        if faces.len() < 2 {
            continue;
        }
        let across = |f: u32, k: usize, _| Some(neighbour[3 * f as usize + k]).filter(|&g| g != NONE);
        split += split_fans(v as u32, faces, &mesh.triangles, &mut triangles, &mut fan, across, || {
            positions.push(mesh.positions[v]);
            positions.len() as u32 - 1
        });
    }
    (triangles, positions, split as usize)
}

/// Splits vertex `v` into one vertex per fan of its faces (`faces`, from [`vertex_faces`] of
/// `triangles`): two faces are in one fan when joined through edges at `v` that
/// `across(face, k, w)` crosses into a face (edge k of the face runs t\[k\] → t\[k + 1\], w is
/// its other end; `None`: a boundary, or a barrier such as a cut). The fan of the lowest face
/// keeps `v`; `copy()` makes the vertex of each other fan (in order of their first face), and
/// it replaces `v` in those faces of `out`. `fan` is scratch. Returns the number of copies.
pub(crate) fn split_fans(
    v: u32,
    faces: &[u32],
    triangles: &[[u32; 3]],
    out: &mut [[u32; 3]],
    fan: &mut Vec<u32>,
    across: impl Fn(u32, usize, u32) -> Option<u32>,
    mut copy: impl FnMut() -> u32,
) -> u32 {
    // Fans: flood fill among the vertex's faces through edges that contain the vertex.
    fan.clear();
    fan.resize(faces.len(), NONE);
    let mut n_fans = 0;
    for s in 0..faces.len() {
        if fan[s] != NONE {
            continue;
        }
        fan[s] = n_fans;
        let mut stack = vec![s];
        while let Some(i) = stack.pop() {
            let f = faces[i];
            let t = triangles[f as usize];
            for k in 0..3 {
                let w = if t[k] == v {
                    t[(k + 1) % 3]
                } else if t[(k + 1) % 3] == v {
                    t[k]
                } else {
                    continue;
                };
                let Some(g) = across(f, k, w) else { continue };
                if let Some(j) = faces.iter().position(|&h| h == g) {
                    if fan[j] == NONE {
                        fan[j] = n_fans;
                        stack.push(j);
                    }
                }
            }
        }
        n_fans += 1;
    }
    for extra in 1..n_fans {
        let c = copy();
        for (i, &f) in faces.iter().enumerate() {
            if fan[i] == extra {
                for x in &mut out[f as usize] {
                    if *x == v {
                        *x = c;
                    }
                }
            }
        }
    }
    n_fans.saturating_sub(1)
}

/// Boundary loops with the faces on their left, each starting at its lowest vertex. `triangles`
/// are the faces before re-orientation (corner `k` ↔ `neighbour[3f + k]`), `flipped` says which
/// faces end reversed.
fn boundary_loops(triangles: &[[u32; 3]], neighbour: &[u32], flipped: &[bool], nv: usize) -> Vec<Vec<u32>> {
    let mut next = vec![NONE; nv];
    for (f, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            if neighbour[3 * f + k] == NONE {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let (a, b) = if flipped[f] { (b, a) } else { (a, b) };
                next[a as usize] = b;
            }
        }
    }
    follow_loops(&next)
}

/// The loops of the successor map `next` (`NONE`: no boundary edge starts there), each from its
/// lowest vertex, in order of it.
pub(crate) fn follow_loops(next: &[u32]) -> Vec<Vec<u32>> {
    let mut loops = Vec::new();
    let mut seen = vec![false; next.len()];
    for s in 0..next.len() {
        if next[s] == NONE || seen[s] {
            continue;
        }
        let mut l = Vec::new();
        let mut v = s as u32;
        while !seen[v as usize] {
            seen[v as usize] = true;
            l.push(v);
            v = next[v as usize];
        }
        loops.push(l);
    }
    loops
}

/// Length of the closed polyline through `l`, mm.
pub(crate) fn loop_length(positions: &[DVec3], l: &[u32]) -> f64 {
    (0..l.len()).map(|i| positions[l[i] as usize].distance(positions[l[(i + 1) % l.len()] as usize])).sum()
}

/// Figures of the whole analysed mesh (the stage's report, without `machined`).
pub fn report(topo: &Topology) -> MeshReport {
    let faces: Vec<usize> = (0..topo.mesh.triangles.len()).collect();
    let components: Vec<&ComponentInfo> = topo.components.iter().collect();
    figures(topo, &faces, &components)
}

/// The same figures for component `c` alone (its pinch splits and re-orientations included in
/// the whole mesh's counts).
pub fn component_report(topo: &Topology, c: usize) -> MeshReport {
    let faces: Vec<usize> = (0..topo.mesh.triangles.len()).filter(|&f| topo.face_component[f] as usize == c).collect();
    figures(topo, &faces, &[&topo.components[c]])
}

fn figures(topo: &Topology, faces: &[usize], components: &[&ComponentInfo]) -> MeshReport {
    let mut used = vec![false; topo.mesh.positions.len()];
    for &f in faces {
        for v in topo.mesh.triangles[f] {
            used[v as usize] = true;
        }
    }
    let positions: Vec<DVec3> = topo.mesh.positions.iter().zip(&used).filter(|(_, &u)| u).map(|(p, _)| *p).collect();
    let (lo, hi) = weld::bounding_box(&positions);
    let loop_vertex_counts: Vec<usize> =
        components.iter().flat_map(|c| c.loops.iter().map(|&l| topo.loops[l].len())).collect();
    let vertices: usize = components.iter().map(|c| c.vertices).sum();
    let edges: usize = components.iter().map(|c| c.edges).sum();
    MeshReport {
        vertices,
        faces: faces.len(),
        edges,
        components: components.len(),
        boundary_loops: loop_vertex_counts.len(),
        loop_vertex_counts,
        euler_characteristic: vertices as i64 - edges as i64 + faces.len() as i64,
        genus: components.iter().map(|c| c.genus()).sum(),
        closed: components.iter().all(|c| c.closed()),
        degenerate_faces_dropped: 0,
        duplicate_faces_dropped: 0,
        pinch_vertices_split: topo.pinch_vertices_split,
        faces_reoriented: topo.faces_reoriented,
        faces_in_other_components: 0,
        area_mm2: components.iter().map(|c| c.area).sum(),
        bbox: [lo.to_array(), hi.to_array()],
        machined: None,
        handle_cuts: Vec::new(),
    }
}

/// The component with the largest area (ties: the lowest), cut out with its loops.
pub fn largest_component(topo: &Topology) -> (usize, Component) {
    let best = (0..topo.components.len())
        .max_by(|&a, &b| topo.components[a].area.total_cmp(&topo.components[b].area).then(b.cmp(&a)))
        .expect("at least one component");
    let triangles: Vec<[u32; 3]> = topo
        .mesh
        .triangles
        .iter()
        .zip(&topo.face_component)
        .filter(|(_, &c)| c as usize == best)
        .map(|(t, _)| *t)
        .collect();
    let mut remap = vec![NONE; topo.mesh.positions.len()];
    let mut positions = Vec::new();
    for t in &triangles {
        for &v in t {
            if remap[v as usize] == NONE {
                remap[v as usize] = positions.len() as u32;
                positions.push(topo.mesh.positions[v as usize]);
            }
        }
    }
    let mesh = TriMesh { positions, triangles: triangles.iter().map(|t| t.map(|v| remap[v as usize])).collect() };
    let loops = topo.components[best]
        .loops
        .iter()
        .map(|&l| topo.loops[l].iter().map(|&v| remap[v as usize]).collect())
        .collect();
    (best, Component { mesh, loops })
}
