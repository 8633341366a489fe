//! The map layout: the scale bar's lengths, clipping to the window, equal aspect.

use super::layout::*;

#[test]
fn nice_lengths_are_one_two_five() {
    assert_eq!(nice_length(730.0), 500.0);
    assert_eq!(nice_length(2100.0), 2000.0);
    assert_eq!(nice_length(1.0), 1.0);
    assert_eq!(nice_length(0.0), 1.0);
    assert_eq!(format_metres(2000.0), "2 km");
    assert_eq!(format_metres(500.0), "500 m");
}

#[test]
fn clipping_keeps_the_inside_part() {
    let bx = [0.0, 0.0, 10.0, 10.0];
    assert_eq!(
        clip_segment([-5.0, 5.0], [5.0, 5.0], bx),
        Some(([0.0, 5.0], [5.0, 5.0]))
    );
    assert_eq!(clip_segment([-5.0, 20.0], [5.0, 20.0], bx), None);
    assert_eq!(
        clip_segment([1.0, 1.0], [2.0, 2.0], bx),
        Some(([1.0, 1.0], [2.0, 2.0]))
    );
}

#[test]
fn layout_keeps_equal_aspect() {
    // A long thin corridor: 10 km by 500 m.
    let l = Layout::new([0.0, 0.0, 10_000.0, 500.0], 1600, 400);
    let sx = l.plot_w as f64 / (l.x1 - l.x0);
    let sy = l.plot_h as f64 / (l.y1 - l.y0);
    assert!((sx - sy).abs() / sx < 1e-9, "{sx} vs {sy}");
    assert!(l.x0 < 0.0 && l.x1 > 10_000.0 && l.y0 < 0.0 && l.y1 > 500.0);
    assert!(l.plot_h >= 400);
}
