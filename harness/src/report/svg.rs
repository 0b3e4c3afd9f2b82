//! Plots as inline SVG, written by hand: a few series over a shared x axis, with shaded bands
//! (a golden's accepted ranges) drawn behind them and vertical marks (where a case fails). No
//! script and no font files: the page's own text and a handful of SVG elements.

use std::fmt::Write;

use super::page::esc;

/// A series of points.
#[derive(Debug, Clone, Default)]
pub struct Series {
    /// Its name in the legend.
    pub name: String,
    /// (x, y) points in x order; drawn as a line with a dot per point when few.
    pub points: Vec<(f64, f64)>,
    /// Drawn as steps (a count that holds until the next point) rather than straight lines.
    pub steps: bool,
    /// Drawn as dots only (values of separate things, such as one per motor).
    pub dots: bool,
}

/// A band: at x, y may lie in `lo..=hi` (drawn behind the series).
#[derive(Debug, Clone, Default)]
pub struct Band {
    /// (x, lo, hi) in x order.
    pub points: Vec<(f64, f64, f64)>,
}

/// One plot.
#[derive(Debug, Clone, Default)]
pub struct Plot {
    /// Title above it.
    pub title: String,
    /// What x counts.
    pub x_label: String,
    /// What y is.
    pub y_label: String,
    /// The series.
    pub series: Vec<Series>,
    /// Bands behind them.
    pub bands: Vec<Band>,
    /// Vertical marks at these x, each with a short label (a failure).
    pub marks: Vec<(f64, String)>,
    /// Windows: at x, a value should lie in `lo..=hi` (drawn as a shaded bar behind the series).
    pub windows: Vec<(f64, f64, f64)>,
    /// Labels under the x axis at these x (things, not numbers: motors); empty: the axis's
    /// two ends are numbered.
    pub x_ticks: Vec<(f64, String)>,
    /// What the bands and windows stand for, in the legend (default "golden range").
    pub band_label: Option<String>,
}

const W: f64 = 640.0;
const H: f64 = 236.0;
const L: f64 = 64.0;
const R: f64 = 16.0;
/// Top margin: the title, then the legend in one row under it, clear of the data and marks.
const T: f64 = 42.0;
const B: f64 = 40.0;
const COLOURS: [&str; 6] = ["#1f5fbf", "#c0392b", "#2e8b57", "#8e44ad", "#d35400", "#555"];

fn nice(v: f64) -> String {
    if v.abs() >= 1000.0 || v.fract() == 0.0 { format!("{v:.0}") } else { format!("{v:.2}") }
}

/// Where the legend's `i`th entry goes: one row under the title, left to right, wrapping to
/// the plot's width (an entry is a 16 px swatch and its name at about 6.5 px a character).
fn legend_at(names: &[&str], i: usize) -> (f64, f64) {
    let (mut x, mut y) = (L, 30.0);
    for (k, n) in names.iter().enumerate() {
        let w = 28.0 + 6.5 * n.chars().count() as f64;
        if x + w > W - R && x > L {
            (x, y) = (L, y + 12.0);
        }
        if k == i {
            break;
        }
        x += w;
    }
    (x, y)
}

impl Plot {
    /// The plot as an `<svg>` element with a `data-plot` attribute naming it (tests find plots
    /// by it) and a `<title>` for screen readers.
    pub fn to_svg(&self, id: &str) -> String {
        let xs = self.series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
        let xs = xs.chain(self.bands.iter().flat_map(|b| b.points.iter().map(|p| p.0)));
        let xs = xs.chain(self.marks.iter().map(|m| m.0));
        let xs = xs.chain(self.windows.iter().flat_map(|w| [w.0 - 0.5, w.0 + 0.5]));
        let (mut x0, mut x1) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
        let ys = self.series.iter().flat_map(|s| s.points.iter().map(|p| p.1));
        let ys = ys.chain(self.bands.iter().flat_map(|b| b.points.iter().flat_map(|p| [p.1, p.2])));
        let ys = ys.chain(self.windows.iter().flat_map(|w| [w.1, w.2]));
        let (mut y0, mut y1) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| (a.min(y), b.max(y)));
        if !x0.is_finite() {
            (x0, x1) = (0.0, 1.0);
        }
        if !y0.is_finite() {
            (y0, y1) = (0.0, 1.0);
        }
        if x1 - x0 < 4.0 && !self.x_ticks.is_empty() {
            // A few labelled things (blocks, motors): half a step of room either side, so no
            // point sits on an axis (numbered axes keep their true ends: no -0.2 s).
            (x0, x1) = (x0 - 0.5, x1 + 0.5);
        }
        if y1 <= y0 {
            y1 = y0 + 1.0;
        }
        let (lo, hi) = (y0, y1);
        let pad = (y1 - y0) * 0.05;
        let (y0, y1) = (y0 - pad, y1 + pad);
        let px = |x: f64| L + (x - x0) / (x1 - x0) * (W - L - R);
        let py = |y: f64| H - B - (y - y0) / (y1 - y0) * (H - T - B);
        let mut s = String::new();
        let _ = write!(
            s,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" data-plot=\"{}\" width=\"{W}\" height=\"{H}\" viewBox=\"0 0 {W} {H}\" \
font-family=\"sans-serif\" font-size=\"11\"><title>{}</title>",
            esc(id),
            esc(&self.title)
        );
        let _ = write!(s, "<text x=\"{L}\" y=\"16\" font-size=\"13\" font-weight=\"bold\">{}</text>", esc(&self.title));
        for b in &self.bands {
            if let [(x, lo, hi)] = b.points[..] {
                // One point has no width to shade: a bar like a window's.
                let w = ((px(x + 0.5) - px(x - 0.5)) * 0.5).max(4.0);
                let _ = write!(
                    s,
                    "<polygon points=\"{0:.1},{2:.1} {1:.1},{2:.1} {1:.1},{3:.1} {0:.1},{3:.1}\" fill=\"#9fd19f\" fill-opacity=\"0.45\" stroke=\"#9fd19f\" stroke-width=\"4\" stroke-linejoin=\"round\"/>",
                    px(x) - w / 2.0,
                    px(x) + w / 2.0,
                    py(hi),
                    py(lo).max(py(hi) + 2.0)
                );
                continue;
            }
            if b.points.is_empty() {
                continue;
            }
            let top: Vec<String> = b.points.iter().map(|p| format!("{:.1},{:.1}", px(p.0), py(p.2))).collect();
            let bottom: Vec<String> = b.points.iter().rev().map(|p| format!("{:.1},{:.1}", px(p.0), py(p.1))).collect();
            let _ = write!(
                s,
                "<polygon points=\"{} {}\" fill=\"#9fd19f\" fill-opacity=\"0.45\" stroke=\"#9fd19f\" stroke-width=\"4\" stroke-linejoin=\"round\"/>",
                top.join(" "),
                bottom.join(" ")
            );
        }
        for (x, lo, hi) in &self.windows {
            let w = ((px(x + 0.5) - px(x - 0.5)) * 0.5).max(4.0);
            let _ = write!(
                s,
                "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{w:.1}\" height=\"{:.1}\" fill=\"#9fd19f\" fill-opacity=\"0.6\"/>",
                px(*x) - w / 2.0,
                py(*hi),
                (py(*lo) - py(*hi)).max(2.0)
            );
        }
        // Axes and their end labels.
        let _ = write!(
            s,
            "<path d=\"M{L},{T} V{} H{}\" fill=\"none\" stroke=\"#444\"/>\
<text x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text><text x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text>\
<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>\
<text x=\"12\" y=\"{}\" transform=\"rotate(-90 12 {})\" text-anchor=\"middle\">{}</text>",
            H - B,
            W - R,
            L - 4.0,
            py(hi) + 4.0,
            nice(hi),
            L - 4.0,
            py(lo) + 4.0,
            nice(lo),
            (L + W - R) / 2.0,
            H - 6.0,
            esc(&self.x_label),
            (T + H - B) / 2.0,
            (T + H - B) / 2.0,
            esc(&self.y_label),
        );
        if self.x_ticks.is_empty() {
            let _ = write!(
                s,
                "<text x=\"{L}\" y=\"{0}\" text-anchor=\"middle\">{1}</text><text x=\"{2}\" y=\"{0}\" text-anchor=\"end\">{3}</text>",
                H - B + 14.0,
                nice(x0),
                W - R,
                nice(x1)
            );
        }
        for (x, label) in &self.x_ticks {
            let _ = write!(
                s,
                "<text x=\"{:.1}\" y=\"{}\" text-anchor=\"middle\">{}</text>",
                px(*x),
                H - B + 14.0,
                esc(label)
            );
        }
        let band_label = self.band_label.clone().unwrap_or_else(|| "golden range".to_string());
        let legend_names: Vec<&str> = self
            .series
            .iter()
            .map(|se| se.name.as_str())
            .chain((!self.bands.is_empty() || !self.windows.is_empty()).then_some(band_label.as_str()))
            .collect();
        for (i, se) in self.series.iter().enumerate() {
            let c = COLOURS[i % COLOURS.len()];
            let mut d = String::new();
            let mut last: Option<(f64, f64)> = None;
            for &(x, y) in &se.points {
                match last {
                    None => {
                        let _ = write!(d, "M{:.1},{:.1}", px(x), py(y));
                    }
                    Some(_) if se.steps => {
                        let _ = write!(d, " H{:.1} V{:.1}", px(x), py(y));
                    }
                    Some(_) => {
                        let _ = write!(d, " L{:.1},{:.1}", px(x), py(y));
                    }
                }
                last = Some((x, y));
            }
            if !se.dots {
                let _ = write!(s, "<path d=\"{d}\" fill=\"none\" stroke=\"{c}\" stroke-width=\"1.6\"/>");
            }
            if se.dots || se.points.len() <= 40 {
                for &(x, y) in &se.points {
                    let _ = write!(
                        s,
                        "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"{}\" fill=\"{c}\"/>",
                        px(x),
                        py(y),
                        if se.dots { 4.0 } else { 2.5 }
                    );
                }
            }
            let (lx, ly) = legend_at(&legend_names, i);
            let _ = write!(
                s,
                "<line x1=\"{lx}\" y1=\"{ly}\" x2=\"{}\" y2=\"{ly}\" stroke=\"{c}\" stroke-width=\"2\"/>\
<text x=\"{}\" y=\"{}\">{}</text>",
                lx + 16.0,
                lx + 20.0,
                ly + 4.0,
                esc(&se.name)
            );
        }
        for (x, label) in &self.marks {
            let _ = write!(
                s,
                "<line x1=\"{0:.1}\" y1=\"{T}\" x2=\"{0:.1}\" y2=\"{1}\" stroke=\"#c0392b\" stroke-dasharray=\"4 3\"/>\
<text x=\"{2:.1}\" y=\"{3}\" fill=\"#c0392b\">{4}</text>",
                px(*x),
                H - B,
                px(*x) + 3.0,
                T + 10.0,
                esc(label)
            );
        }
        if !self.bands.is_empty() || !self.windows.is_empty() {
            let (lx, ly) = legend_at(&legend_names, self.series.len());
            let _ = write!(
                s,
                "<rect x=\"{lx}\" y=\"{}\" width=\"14\" height=\"9\" fill=\"#9fd19f\"/><text x=\"{}\" y=\"{}\">{}</text>",
                ly - 5.0,
                lx + 20.0,
                ly + 4.0,
                esc(&band_label)
            );
        }
        s.push_str("</svg>\n");
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plot_draws_its_series_band_and_marks() {
        let p = Plot {
            title: "LFAP, motor 1".into(),
            x_label: "block".into(),
            y_label: "counts".into(),
            series: vec![Series {
                name: "actual".into(),
                points: vec![(1.0, 5000.0), (2.0, 34835.0)],
                ..Default::default()
            }],
            bands: vec![Band { points: vec![(1.0, 4950.0, 5050.0), (2.0, 4950.0, 5050.0)] }],
            marks: vec![(2.0, "fails".into())],
            ..Default::default()
        };
        let svg = p.to_svg("rt-lfap");
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>\n"));
        assert!(svg.contains("data-plot=\"rt-lfap\""));
        assert!(svg.contains("<polygon"), "the band is drawn");
        assert!(svg.contains("stroke-dasharray"), "the failure is marked");
        assert!(svg.contains(">34835<"), "the axis reaches the out-of-range value");
    }
}
