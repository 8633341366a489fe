//! The little XML this crate writes: one element per line, attributes escaped, numbers with fixed decimals.

use std::fmt::Write;

/// Escape a value for a double-quoted XML attribute ([`mapc_graph::markup::escape`]).
pub fn escape(value: &str) -> String {
    mapc_graph::markup::escape(value)
}

/// A number as SUMO reads it back: two decimals for geometry (SUMO's own precision), more where lengths must
/// survive a round trip within millimetres.
pub fn num(x: f64, decimals: usize) -> String {
    let s = format!("{x:.decimals$}");
    // `-0.00` reads the same but looks like a bug.
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

/// `x1,y1 x2,y2 ...`
pub fn shape(points: &[[f64; 2]]) -> String {
    points
        .iter()
        .map(|p| format!("{},{}", num(p[0], 2), num(p[1], 2)))
        .collect::<Vec<_>>()
        .join(" ")
}

/// One empty element `<tag a="b" .../>` on its own line, indented by `indent` spaces.
pub fn element(out: &mut String, indent: usize, tag: &str, attrs: &[(&str, String)]) {
    open(out, indent, tag, attrs);
    out.push_str("/>\n");
}

/// `<tag a="b" ...>` on its own line (the caller closes it).
pub fn start(out: &mut String, indent: usize, tag: &str, attrs: &[(&str, String)]) {
    open(out, indent, tag, attrs);
    out.push_str(">\n");
}

fn open(out: &mut String, indent: usize, tag: &str, attrs: &[(&str, String)]) {
    let _ = write!(out, "{:indent$}<{tag}", "");
    for (k, v) in attrs {
        let _ = write!(out, " {k}=\"{}\"", escape(v));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attributes_are_escaped_and_numbers_fixed() {
        let mut s = String::new();
        element(
            &mut s,
            2,
            "edge",
            &[("id", "a&<\"b".into()), ("length", num(-0.0001, 2))],
        );
        assert_eq!(s, "  <edge id=\"a&amp;&lt;&quot;b\" length=\"0.00\"/>\n");
        assert_eq!(shape(&[[1.0, 2.004], [3.0, -4.0]]), "1.00,2.00 3.00,-4.00");
    }
}
