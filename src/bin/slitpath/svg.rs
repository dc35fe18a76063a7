//! SVG drawing of a slit map for `slitpath map --svg`: on the left the flattened domain with
//! iso-|w| circles and radial lines (iso-arg w) pulled back through the map, on the right the slit
//! domain itself (unit circle, arc slits, the same circles and radial lines, the image mesh).

use glam::DVec2;
use std::f64::consts::TAU;
use std::fmt::Write;

/// What the drawing needs; all per-vertex arrays share the mesh's vertex order.
pub struct SlitDrawing<'a> {
    pub uv: &'a [DVec2],
    pub w: &'a [DVec2],
    pub triangles: &'a [[u32; 3]],
    pub loops: &'a [Vec<u32>],
    /// `(radius, theta_start, theta_end)` of each arc slit, radians, counter-clockwise.
    pub slits: &'a [(f64, f64, f64)],
    /// Inner circle radius for the annulus map.
    pub inner_radius: Option<f64>,
    pub pole_uv: DVec2,
}

const SIZE: f64 = 480.0;
const MARGIN: f64 = 20.0;
const RADII: usize = 8;
const SPOKES: usize = 16;

pub fn draw(d: &SlitDrawing) -> String {
    let mut svg = String::new();
    let width = 2.0 * SIZE + 3.0 * MARGIN;
    let height = SIZE + 2.0 * MARGIN;
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif">"#
    );
    let _ = writeln!(svg, r##"<rect width="100%" height="100%" fill="#fff"/>"##);

    // Left panel: the flattened domain, y up.
    let (lo, hi) = d
        .uv
        .iter()
        .fold((DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let scale = SIZE / (hi - lo).max_element().max(1e-300);
    let left = |p: DVec2| DVec2::new(MARGIN + (p.x - lo.x) * scale, MARGIN + SIZE - (p.y - lo.y) * scale);
    let modulus: Vec<f64> = d.w.iter().map(|w| w.length()).collect();
    let min_r = d.inner_radius.unwrap_or(0.0);
    let levels: Vec<f64> = (1..RADII).map(|k| min_r + (1.0 - min_r) * k as f64 / RADII as f64).collect();
    for &level in &levels {
        let segments = contour(d.triangles, |v| modulus[v], level, d.uv);
        path(&mut svg, &segments, left, "#3b7dd8", 0.8);
    }
    // Radial lines: arg w unwrapped per triangle relative to its first corner.
    for k in 0..SPOKES {
        let level = spoke_angle(k);
        let mut segments = Vec::new();
        for t in d.triangles {
            let base = arg(d.w[t[0] as usize]);
            let a = t.map(|v| base + wrap(arg(d.w[v as usize]) - base));
            // The tiny triangles around the pole span all angles; skip them.
            if a.iter().fold(f64::NEG_INFINITY, |m, &x| m.max(x)) - a.iter().fold(f64::INFINITY, |m, &x| m.min(x)) > 1.0
            {
                continue;
            }
            for shift in [-TAU, 0.0, TAU] {
                if let Some(s) = triangle_contour(a, level + shift, t.map(|v| d.uv[v as usize])) {
                    segments.push(s);
                }
            }
        }
        path(&mut svg, &segments, left, "#d8733b", 0.8);
    }
    for l in d.loops {
        polyline(&mut svg, l.iter().map(|&v| left(d.uv[v as usize])), true, "#222", 1.6);
    }
    let p = left(d.pole_uv);
    let _ = writeln!(svg, r##"<circle cx="{:.2}" cy="{:.2}" r="4" fill="#c00"/>"##, p.x, p.y);
    label(&mut svg, MARGIN, "flattened domain S^F (pole in red)");

    // Right panel: the slit domain.
    let c = DVec2::new(2.0 * MARGIN + 1.5 * SIZE, MARGIN + 0.5 * SIZE);
    let right = |w: DVec2| DVec2::new(c.x + w.x * 0.48 * SIZE, c.y - w.y * 0.48 * SIZE);
    for t in d.triangles {
        polyline(&mut svg, t.iter().map(|&v| right(d.w[v as usize])), true, "#ddd", 0.3);
    }
    for &level in &levels {
        circle(&mut svg, c, level * 0.48 * SIZE, "#3b7dd8", 0.8);
    }
    for k in 0..SPOKES {
        let dir = DVec2::from_angle(spoke_angle(k));
        polyline(&mut svg, [right(dir * min_r), right(dir)].into_iter(), false, "#d8733b", 0.8);
    }
    for r in std::iter::once(1.0).chain(d.inner_radius) {
        circle(&mut svg, c, r * 0.48 * SIZE, "#222", 1.6);
    }
    for &(r, start, end) in d.slits {
        let span = (end - start).rem_euclid(TAU);
        let n = (span / TAU * 256.0).ceil().max(2.0) as usize;
        let arc = (0..=n).map(|i| right(DVec2::from_angle(start + span * i as f64 / n as f64) * r));
        polyline(&mut svg, arc, false, "#c00", 2.4);
    }
    label(&mut svg, 2.0 * MARGIN + SIZE, "slit domain S^S (slits in red)");
    svg.push_str("</svg>\n");
    svg
}

/// Angle of radial line `k`, away from the ±π cut.
fn spoke_angle(k: usize) -> f64 {
    -std::f64::consts::PI + TAU * (k as f64 + 0.5) / SPOKES as f64
}

fn circle(svg: &mut String, centre: DVec2, r: f64, colour: &str, width: f64) {
    let _ = writeln!(
        svg,
        r#"<circle cx="{:.2}" cy="{:.2}" r="{r:.2}" fill="none" stroke="{colour}" stroke-width="{width}"/>"#,
        centre.x, centre.y
    );
}

fn arg(w: DVec2) -> f64 {
    w.y.atan2(w.x)
}

fn wrap(a: f64) -> f64 {
    (a + std::f64::consts::PI).rem_euclid(TAU) - std::f64::consts::PI
}

/// Segments of the level set `f = level` of a per-vertex function, linearly interpolated.
fn contour(triangles: &[[u32; 3]], f: impl Fn(usize) -> f64, level: f64, uv: &[DVec2]) -> Vec<[DVec2; 2]> {
    triangles
        .iter()
        .filter_map(|t| triangle_contour(t.map(|v| f(v as usize)), level, t.map(|v| uv[v as usize])))
        .collect()
}

fn triangle_contour(values: [f64; 3], level: f64, p: [DVec2; 3]) -> Option<[DVec2; 2]> {
    let mut hits = Vec::with_capacity(2);
    for k in 0..3 {
        let (a, b) = (values[k] - level, values[(k + 1) % 3] - level);
        if (a < 0.0) != (b < 0.0) {
            let s = a / (a - b);
            hits.push(p[k].lerp(p[(k + 1) % 3], s));
        }
    }
    (hits.len() == 2).then(|| [hits[0], hits[1]])
}

fn path(svg: &mut String, segments: &[[DVec2; 2]], map: impl Fn(DVec2) -> DVec2, colour: &str, width: f64) {
    if segments.is_empty() {
        return;
    }
    let mut d = String::new();
    for [a, b] in segments {
        let (a, b) = (map(*a), map(*b));
        let _ = write!(d, "M{:.2} {:.2}L{:.2} {:.2}", a.x, a.y, b.x, b.y);
    }
    let _ = writeln!(svg, r#"<path d="{d}" fill="none" stroke="{colour}" stroke-width="{width}"/>"#);
}

fn polyline(svg: &mut String, points: impl Iterator<Item = DVec2>, closed: bool, colour: &str, width: f64) {
    let pts: Vec<String> = points.map(|p| format!("{:.2},{:.2}", p.x, p.y)).collect();
    let tag = if closed { "polygon" } else { "polyline" };
    let _ =
        writeln!(svg, r#"<{tag} points="{}" fill="none" stroke="{colour}" stroke-width="{width}"/>"#, pts.join(" "));
}

fn label(svg: &mut String, x: f64, text: &str) {
    let _ = writeln!(svg, r##"<text x="{:.1}" y="{:.1}" font-size="13" fill="#444">{text}</text>"##, x, MARGIN - 5.0);
}
