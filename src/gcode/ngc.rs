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
    // One buffer per word and one for the feed, reused move after move.
    let letters: &[char] = if angles.is_some() { &['X', 'Y', 'Z', 'A', 'C'] } else { &['X', 'Y', 'Z'] };
    let mut words: Vec<(char, String)> = letters.iter().map(|&c| (c, String::new())).collect();
    let mut feed = String::new();
    let mut moved = String::new();
    for (i, m) in toolpath.moves.iter().enumerate() {
        let mut values = [m.tip.x, m.tip.y, m.tip.z, 0.0, 0.0];
        if let Some(angles) = &angles {
            (values[3], values[4]) = angles[i];
        }
        for ((_, word), &v) in words.iter_mut().zip(&values) {
            word.clear();
            f.push_num(word, v);
        }
        let rapid = m.kind.is_rapid();
        feed.clear();
        if !rapid {
            f.push_with(&mut feed, m.feed_mm_min, 1);
        }
        moved.clear();
        if modal.write(&mut moved, rapid, &words, (!rapid).then_some(feed.as_str())) {
            line(&moved);
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
        let mut s = String::new();
        self.write(&mut s, rapid, words, feed.as_deref()).then_some(s)
    }

    /// [`Modal::line`] appended to `s`; false when nothing is written.
    fn write(&mut self, s: &mut String, rapid: bool, words: &[(char, String)], feed: Option<&str>) -> bool {
        let unchanged = |w: &(char, String)| self.words.iter().any(|(c, v)| *c == w.0 && *v == w.1);
        if words.iter().all(unchanged) {
            return false;
        }
        let start = s.len();
        if self.rapid != Some(rapid) {
            s.push_str(if rapid { "G0" } else { "G1" });
            self.rapid = Some(rapid);
        }
        for (c, v) in words {
            if self.words.iter().any(|(k, x)| k == c && x == v) {
                continue;
            }
            if s.len() > start {
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
            if self.feed.as_deref() != Some(feed) {
                s.push_str(" F");
                s.push_str(feed);
                self.feed = Some(feed.to_string());
            }
        }
        true
    }
}
