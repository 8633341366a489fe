//! Colours: road classes, the speed scale (red slow, green fast) and a palette for overlaid runs.

use plotters::style::RGBColor;

/// Known road classes, most important first, with their colours. SUMO edge types (`highway.motorway`) use the part
/// after the dot.
const CLASS_COLORS: [(&str, RGBColor); 10] = [
    ("motorway", RGBColor(196, 30, 58)),
    ("motorway_link", RGBColor(245, 130, 32)),
    ("trunk", RGBColor(128, 52, 160)),
    ("trunk_link", RGBColor(186, 128, 214)),
    ("primary", RGBColor(31, 104, 196)),
    ("primary_link", RGBColor(110, 165, 230)),
    ("secondary", RGBColor(34, 139, 76)),
    ("secondary_link", RGBColor(120, 190, 140)),
    ("tertiary", RGBColor(150, 110, 40)),
    ("residential", RGBColor(140, 140, 140)),
];

/// Colours for classes outside the table, handed out in order of first appearance.
const SPARE_COLORS: [RGBColor; 6] = [
    RGBColor(0, 128, 128),
    RGBColor(214, 97, 0),
    RGBColor(200, 0, 160),
    RGBColor(110, 80, 20),
    RGBColor(60, 60, 180),
    RGBColor(90, 90, 90),
];

/// `highway.motorway` -> `motorway`; other names unchanged.
pub fn base_class(class: &str) -> &str {
    class.rsplit('.').next().unwrap_or(class)
}

/// Rank of a class for drawing order and the legend: known classes by importance, then the others.
pub fn class_rank(class: &str) -> usize {
    let c = base_class(class);
    CLASS_COLORS
        .iter()
        .position(|(k, _)| *k == c)
        .unwrap_or(CLASS_COLORS.len())
}

/// The colour of each class in `classes` (sorted by [`class_rank`], then name); unknown classes get spare colours.
pub fn class_colors(classes: &[String]) -> Vec<(String, RGBColor)> {
    let mut sorted: Vec<&String> = classes.iter().collect();
    sorted.sort_by(|a, b| class_rank(a).cmp(&class_rank(b)).then(a.cmp(b)));
    sorted.dedup();
    let mut spare = 0;
    sorted
        .into_iter()
        .map(|c| {
            let color = CLASS_COLORS
                .iter()
                .find(|(k, _)| *k == base_class(c))
                .map(|(_, col)| *col)
                .unwrap_or_else(|| {
                    let col = SPARE_COLORS[spare % SPARE_COLORS.len()];
                    spare += 1;
                    col
                });
            (c.clone(), color)
        })
        .collect()
}

/// The speed scale's stops (fraction of the top speed, RGB); `mapc view`'s page interpolates the same.
pub const SPEED_STOPS: [(f64, [f64; 3]); 5] = [
    (0.0, [165.0, 0.0, 38.0]),
    (0.25, [244.0, 109.0, 67.0]),
    (0.5, [254.0, 224.0, 139.0]),
    (0.75, [166.0, 217.0, 106.0]),
    (1.0, [0.0, 104.0, 55.0]),
];

/// Red (slow) through yellow to green (fast), as in the paper's time-space figures. `t` is clamped to [0, 1].
pub fn speed_color(t: f64) -> RGBColor {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    for w in SPEED_STOPS.windows(2) {
        let ((t0, c0), (t1, c1)) = (w[0], w[1]);
        if t <= t1 {
            let f = (t - t0) / (t1 - t0);
            let mix = |i: usize| (c0[i] + f * (c1[i] - c0[i])).round() as u8;
            return RGBColor(mix(0), mix(1), mix(2));
        }
    }
    RGBColor(0, 104, 55)
}

/// Distinct line colours for overlaid runs.
pub fn run_color(i: usize) -> RGBColor {
    const RUNS: [RGBColor; 8] = [
        RGBColor(31, 119, 180),
        RGBColor(214, 39, 40),
        RGBColor(44, 160, 44),
        RGBColor(255, 127, 14),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(23, 190, 207),
    ];
    RUNS[i % RUNS.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speed_scale_runs_red_to_green() {
        let slow = speed_color(0.0);
        let fast = speed_color(1.0);
        assert!(slow.0 > slow.1, "slow is red: {slow:?}");
        assert!(fast.1 > fast.0, "fast is green: {fast:?}");
        assert_eq!(speed_color(-3.0), slow);
        assert_eq!(speed_color(f64::NAN), slow);
    }

    #[test]
    fn classes_get_distinct_colours_in_importance_order() {
        let classes: Vec<String> = [
            "primary",
            "highway.motorway",
            "weird",
            "motorway_link",
            "other",
        ]
        .map(String::from)
        .to_vec();
        let cc = class_colors(&classes);
        assert_eq!(cc[0].0, "highway.motorway");
        assert_eq!(cc[1].0, "motorway_link");
        assert_eq!(cc[2].0, "primary");
        let mut colors: Vec<_> = cc.iter().map(|(_, c)| (c.0, c.1, c.2)).collect();
        colors.sort();
        colors.dedup();
        assert_eq!(colors.len(), 5);
    }
}
