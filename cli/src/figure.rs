//! The paper's frame-error figures as SVG (`upetrack compare --figures`):
//! per algorithm, the frame error in pixels over the frames (Fig. 9) and its
//! median, quartiles and range (Fig. 10), for one scene.

use std::fmt::Write;

use upetrack_io::eval::{quantile, FrameError};

/// Plot area, SVG units.
const WIDTH: f64 = 640.0;
const HEIGHT: f64 = 300.0;
const MARGIN_LEFT: f64 = 50.0;
const MARGIN_BOTTOM: f64 = 40.0;
const MARGIN_TOP: f64 = 30.0;
/// The box plot's panel, right of the curves.
const BOX_PANEL: f64 = 220.0;

/// One colour per algorithm, in the order given (UPETrack's first).
const COLOURS: [&str; 6] = [
    "#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b",
];

/// One algorithm's series: its name and the frame errors of its run.
pub struct Series<'a> {
    /// Algorithm name.
    pub name: &'a str,
    /// Errors of the frames with ground truth, in order.
    pub errors: &'a [FrameError],
}

/// The SVG of `series` on `scene`; `occluded_from` marks the first occluded frame.
pub fn frame_error_svg(scene: &str, series: &[Series<'_>], occluded_from: Option<usize>) -> String {
    let frames = series
        .iter()
        .flat_map(|s| s.errors.iter().map(|e| e.frame))
        .max()
        .unwrap_or(0)
        .max(1) as f64;
    let top = series
        .iter()
        .flat_map(|s| s.errors.iter().map(|e| e.px))
        .filter(|v| v.is_finite())
        .fold(1.0f64, f64::max);
    // A round upper bound for the axis.
    let step = [0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0]
        .into_iter()
        .find(|s| top / s <= 6.0)
        .unwrap_or(200.0);
    let ymax = (top / step).ceil() * step;
    let plot_w = WIDTH - MARGIN_LEFT - 10.0;
    let plot_h = HEIGHT - MARGIN_TOP - MARGIN_BOTTOM;
    let x = |f: f64| MARGIN_LEFT + plot_w * f / frames;
    let y = |v: f64| MARGIN_TOP + plot_h * (1.0 - (v / ymax).clamp(0.0, 1.0));
    let total_w = WIDTH + BOX_PANEL;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{total_w}" height="{HEIGHT}" viewBox="0 0 {total_w} {HEIGHT}" font-family="sans-serif" font-size="11">"#
    );
    let _ = writeln!(
        s,
        r#"<rect width="{total_w}" height="{HEIGHT}" fill="white"/>"#
    );
    let _ = writeln!(
        s,
        r#"<text x="{MARGIN_LEFT}" y="18" font-size="13">{}: frame error (px) per frame</text>"#,
        escape(scene)
    );
    // Axes and grid.
    let mut v = 0.0;
    while v <= ymax + 1e-9 {
        let yy = y(v);
        let _ = writeln!(
            s,
            r##"<line x1="{MARGIN_LEFT}" x2="{}" y1="{yy:.1}" y2="{yy:.1}" stroke="#ddd"/><text x="{}" y="{:.1}" text-anchor="end">{v}</text>"##,
            MARGIN_LEFT + plot_w,
            MARGIN_LEFT - 4.0,
            yy + 4.0
        );
        v += step;
    }
    let base = MARGIN_TOP + plot_h;
    let _ = writeln!(
        s,
        r#"<line x1="{MARGIN_LEFT}" x2="{}" y1="{base}" y2="{base}" stroke="black"/><text x="{}" y="{}" text-anchor="middle">frame</text>"#,
        MARGIN_LEFT + plot_w,
        MARGIN_LEFT + plot_w / 2.0,
        HEIGHT - 8.0
    );
    for k in 0..=4 {
        let f = frames * k as f64 / 4.0;
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{}" text-anchor="middle">{:.0}</text>"#,
            x(f),
            base + 14.0,
            f
        );
    }
    if let Some(o) = occluded_from {
        let xo = x(o as f64);
        let _ = writeln!(
            s,
            r##"<line x1="{xo:.1}" x2="{xo:.1}" y1="{MARGIN_TOP}" y2="{base}" stroke="#555" stroke-dasharray="4 3"/><text x="{:.1}" y="{}" fill="#555">occluded from here</text>"##,
            xo + 3.0,
            MARGIN_TOP + 10.0
        );
    }
    // Curves.
    for (k, ser) in series.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        let points: Vec<String> = ser
            .errors
            .iter()
            .filter(|e| e.px.is_finite())
            .map(|e| format!("{:.1},{:.1}", x(e.frame as f64), y(e.px)))
            .collect();
        let _ = writeln!(
            s,
            r#"<polyline fill="none" stroke="{colour}" stroke-width="1.5" points="{}"/>"#,
            points.join(" ")
        );
        let ly = MARGIN_TOP + 8.0 + 14.0 * k as f64;
        let _ = writeln!(
            s,
            r#"<line x1="{}" x2="{}" y1="{ly}" y2="{ly}" stroke="{colour}" stroke-width="2"/><text x="{}" y="{}">{}</text>"#,
            MARGIN_LEFT + 10.0,
            MARGIN_LEFT + 28.0,
            MARGIN_LEFT + 32.0,
            ly + 4.0,
            escape(ser.name)
        );
    }
    // Box plot: median, quartiles, range, on the same axis.
    let _ = writeln!(
        s,
        r#"<text x="{}" y="18" font-size="13">median, IQR, range</text>"#,
        WIDTH + 10.0
    );
    let slot = (BOX_PANEL - 20.0) / series.len().max(1) as f64;
    for (k, ser) in series.iter().enumerate() {
        let px: Vec<f64> = ser
            .errors
            .iter()
            .map(|e| e.px)
            .filter(|v| v.is_finite())
            .collect();
        if px.is_empty() {
            continue;
        }
        let colour = COLOURS[k % COLOURS.len()];
        let cx = WIDTH + 10.0 + slot * (k as f64 + 0.5);
        let (lo, q1, med, q3, hi) = (
            quantile(&px, 0.0),
            quantile(&px, 0.25),
            quantile(&px, 0.5),
            quantile(&px, 0.75),
            quantile(&px, 1.0),
        );
        let half = (slot * 0.3).min(18.0);
        let _ = writeln!(
            s,
            r#"<line x1="{cx:.1}" x2="{cx:.1}" y1="{:.1}" y2="{:.1}" stroke="{colour}"/><rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="{colour}" fill-opacity="0.25" stroke="{colour}"/><line x1="{:.1}" x2="{:.1}" y1="{:.1}" y2="{:.1}" stroke="{colour}" stroke-width="2"/><text x="{cx:.1}" y="{}" text-anchor="middle">{}</text>"#,
            y(lo),
            y(hi),
            cx - half,
            y(q3),
            2.0 * half,
            (y(q1) - y(q3)).max(0.5),
            cx - half,
            cx + half,
            y(med),
            y(med),
            base + 14.0,
            escape(ser.name)
        );
    }
    s.push_str("</svg>\n");
    s
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn errors(px: &[f64]) -> Vec<FrameError> {
        px.iter()
            .enumerate()
            .map(|(frame, &px)| FrameError { frame, mm: px, px })
            .collect()
    }

    #[test]
    fn the_figure_has_a_curve_and_a_box_per_algorithm_on_one_axis() {
        let (a, b) = (
            errors(&[1.0, 2.0, 3.0, 4.0]),
            errors(&[2.0, 2.0, 9.0, f64::NAN]),
        );
        let svg = frame_error_svg(
            "s<1>",
            &[
                Series {
                    name: "upetrack",
                    errors: &a,
                },
                Series {
                    name: "cpd",
                    errors: &b,
                },
            ],
            Some(2),
        );
        assert_eq!(svg.matches("<polyline").count(), 2);
        assert_eq!(svg.matches("<rect x=").count(), 2);
        assert!(svg.contains("s&lt;1&gt;") && svg.contains("occluded from here"));
        // 9 px is the top: the axis runs to 10 in steps of 2; NaN is left out.
        assert!(svg.contains(">10</text>") && !svg.contains("NaN"));
        // UPETrack's curve: frame 0 at the left edge, 1 px at 90 % of the height.
        let y1 = MARGIN_TOP + (HEIGHT - MARGIN_TOP - MARGIN_BOTTOM) * 0.9;
        assert!(
            svg.contains(&format!("points=\"{MARGIN_LEFT:.1},{y1:.1} ")),
            "{svg}"
        );
    }
}
