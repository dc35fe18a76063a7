//! The G-code posts: LinuxCNC and GRBL (3-axis) and the A/C table-table post (LinuxCNC dialect).

use super::{ac, header_lines, Fmt, GcodeError, GcodeOptions, Post};
use crate::toolpath::Toolpath;
use glam::DVec3;

/// Largest deviation of a 3-axis post's tool axis from +Z.
const VERTICAL_TOLERANCE: f64 = 1e-9;

pub(super) fn write(toolpath: &Toolpath, options: &GcodeOptions) -> Result<String, GcodeError> {
    let post = options.post;
    let f = Fmt { decimals: options.decimals };
    let angles = if post == Post::Ac {
        let axes: Vec<DVec3> = toolpath.moves.iter().map(|m| m.axis).collect();
        Some(ac::ac_angles(&axes)?)
    } else {
        for (index, m) in toolpath.moves.iter().enumerate() {
            if m.axis.distance(DVec3::Z) > VERTICAL_TOLERANCE {
                let a = m.axis;
                return Err(GcodeError::NotThreeAxis { post, index, x: a.x, y: a.y, z: a.z });
            }
        }
        None
    };

    let mut out = String::new();
    let mut line = |s: &str| {
        out.push_str(s);
        out.push('\n');
    };
    line(match post {
        Post::LinuxCnc => "(slitpath toolpath - post linuxcnc: 3-axis, tool tip coordinates)",
        Post::Grbl => "(slitpath toolpath - post grbl: 3-axis, tool tip coordinates)",
        _ => "(slitpath toolpath - post ac: 5-axis table-table A/C, tool tip coordinates, TCP control must be on)",
    });
    for l in header_lines(toolpath, options, &f) {
        line(&format!("({l})"));
    }
    let tool = toolpath.tool;
    match post {
        Post::Grbl => {
            line(&format!("(- load tool T{} before running: GRBL has no tool changer)", tool.number));
            line("G21 G90 G17 G94 G40");
        }
        _ => {
            if post == Post::Ac {
                line("(- tool axis = Rz[C] Rx[A] [0 0 1] in the part frame, degrees, C continuous)");
            }
            line("G21 G90 G17 G94 G40 G49");
            if options.blend_tolerance_mm > 0.0 {
                line(&format!("G64 P{}", f.num(options.blend_tolerance_mm)));
            } else {
                line("G61");
            }
            line(&format!("T{} M6", tool.number));
            line(&format!("G43 H{}", tool.number));
        }
    }
    line(&format!("S{} M3", f.with(tool.spindle_rpm, 1)));

    let mut modal = Modal::default();
    // Safe height first, at the unknown start position.
    let first = toolpath.moves[0].tip;
    if let Some(l) = modal.line(true, &[('Z', f.num(first.z))], None) {
        line(&l);
    }
    for (i, m) in toolpath.moves.iter().enumerate() {
        let mut words = vec![('X', f.num(m.tip.x)), ('Y', f.num(m.tip.y)), ('Z', f.num(m.tip.z))];
        if let Some(angles) = &angles {
            let (a, c) = angles[i];
            words.push(('A', f.num(a)));
            words.push(('C', f.num(c)));
        }
        let rapid = m.kind.is_rapid();
        let feed = (!rapid).then(|| f.with(m.feed_mm_min, 1));
        if let Some(l) = modal.line(rapid, &words, feed) {
            line(&l);
        }
    }
    line("M5");
    line("M30");
    Ok(out)
}

/// The modal state of the program as written so far (words as formatted).
#[derive(Default)]
struct Modal {
    rapid: Option<bool>,
    words: Vec<(char, String)>,
    feed: Option<String>,
}

impl Modal {
    /// The line for a move to `words`, or None when no coordinate changes at the output
    /// precision (then nothing is written and the state is unchanged).
    fn line(&mut self, rapid: bool, words: &[(char, String)], feed: Option<String>) -> Option<String> {
        let changed: Vec<&(char, String)> =
            words.iter().filter(|w| !self.words.iter().any(|(c, v)| *c == w.0 && *v == w.1)).collect();
        if changed.is_empty() {
            return None;
        }
        let mut s = String::new();
        if self.rapid != Some(rapid) {
            s.push_str(if rapid { "G0" } else { "G1" });
            self.rapid = Some(rapid);
        }
        for (c, v) in changed {
            if !s.is_empty() {
                s.push(' ');
            }
            s.push(*c);
            s.push_str(v);
            match self.words.iter_mut().find(|(k, _)| k == c) {
                Some(slot) => slot.1.clone_from(v),
                None => self.words.push((*c, v.clone())),
            }
        }
        if let Some(feed) = feed {
            if self.feed.as_ref() != Some(&feed) {
                s.push_str(" F");
                s.push_str(&feed);
                self.feed = Some(feed);
            }
        }
        Some(s)
    }
}
