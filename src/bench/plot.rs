//! Line and bar charts for results/ (SVG: no font files needed, readable in any browser or on GitHub).

use anyhow::{Context, Result};
use plotters::prelude::*;
use std::path::Path;

/// One named line.
pub struct Series {
    /// Legend label.
    pub label: String,
    /// Points (x, y).
    pub points: Vec<(f64, f64)>,
}

/// Axis options.
#[derive(Clone, Copy, Default)]
pub struct Axes {
    /// x on a log10 scale (values must be > 0).
    pub log_x: bool,
    /// y on a log10 scale (values must be > 0; for times and sizes that span decades).
    pub log_y: bool,
    /// Start y at zero (counts); otherwise fit y to the data (ignored with `log_y`).
    pub zero_y: bool,
}

/// `x` for a tick label: three significant digits at most, thousands as `k`, millions as `M`,
/// billions as `G` (100 k, 1 M, 2.5 M, 0.01).
pub fn human(x: f64) -> String {
    let (v, unit) = match x.abs() {
        a if a >= 1e9 => (x / 1e9, " G"),
        a if a >= 1e6 => (x / 1e6, " M"),
        a if a >= 1e3 => (x / 1e3, " k"),
        _ => (x, ""),
    };
    if v == 0.0 {
        return "0".into();
    }
    // Three significant digits, trailing zeros dropped.
    let digits = (2 - v.abs().log10().floor() as i32).clamp(0, 9) as usize;
    let mut t = format!("{v:.digits$}");
    if t.contains('.') {
        t = t.trim_end_matches('0').trim_end_matches('.').to_string();
    }
    format!("{t}{unit}")
}

/// A log axis drawn in log10 units: its tick label at `x`. Over a decade or more only the powers
/// of ten are labelled (1, 10, 100 k, 1 M); over less, every tick.
fn log_label(x: f64, span: f64) -> String {
    if span >= 1.0 && (x - x.round()).abs() > 1e-9 {
        return String::new();
    }
    human(10f64.powf(x))
}

/// Candidate ticks for an axis spanning `span` (log10 units on a log axis): two per decade on a
/// log axis over a decade or more, so that the powers of ten (the labelled ones) are among them.
fn tick_count(log: bool, span: f64) -> usize {
    if log && span >= 1.0 {
        (2.0 * span).ceil() as usize + 1
    } else {
        8
    }
}

/// Draws `series` as lines with markers.
pub fn line_chart(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    axes: Axes,
) -> Result<()> {
    let (log_x, log_y) = (axes.log_x, axes.log_y);
    let tx = move |x: f64| if log_x { x.max(1e-12).log10() } else { x };
    let ty = move |y: f64| if log_y { y.max(1e-12).log10() } else { y };
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, (900, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let pts = series.iter().flat_map(|s| s.points.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(x, y) in pts {
        let (x, y) = (tx(x), ty(y));
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if !x0.is_finite() {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    let pad = |a: f64, b: f64| if b > a { (b - a) * 0.05 } else { 1.0 };
    let (px, py) = (pad(x0, x1), pad(y0, y1));
    let y_from = if axes.zero_y && !log_y {
        y0.min(0.0)
    } else {
        y0 - py
    };
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(64)
        .build_cartesian_2d((x0 - px)..(x1 + px), y_from..(y1 + py))?;
    let (xspan, yspan) = (x1 - x0, y1 - y0);
    let xfmt = move |x: &f64| {
        if log_x {
            log_label(*x, xspan)
        } else {
            human(*x)
        }
    };
    let yfmt = move |y: &f64| {
        if log_y {
            log_label(*y, yspan)
        } else {
            human(*y)
        }
    };
    let log_note = |label: &str, log: bool| {
        if log && !label.contains("log") {
            format!("{label} (log scale)")
        } else {
            label.to_string()
        }
    };
    chart
        .configure_mesh()
        .x_labels(tick_count(log_x, xspan))
        .y_labels(tick_count(log_y, yspan))
        .x_desc(log_note(x_label, log_x))
        .y_desc(log_note(y_label, log_y))
        .x_label_formatter(&xfmt)
        .y_label_formatter(&yfmt)
        .draw()?;
    for (i, s) in series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let pts: Vec<(f64, f64)> = s.points.iter().map(|&(x, y)| (tx(x), ty(y))).collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))?
            .label(s.label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
            });
        chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 3, color.filled())))?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    root.present()
        .with_context(|| format!("{}: cannot draw plot", path.display()))?;
    drop(chart);
    drop(root);
    crate::atomic::write(path, svg)
        .with_context(|| format!("{}: cannot write plot", path.display()))
}

/// One bar series: a value per category; series with the same `stack` are stacked on each other,
/// different stacks stand side by side within a category.
pub struct Bars {
    /// Legend label.
    pub label: String,
    /// One value per category.
    pub values: Vec<f64>,
    /// Stack index (0-based).
    pub stack: usize,
}

/// Draws grouped (and optionally stacked) bars, one group per category.
pub fn bar_chart(
    path: &Path,
    title: &str,
    y_label: &str,
    categories: &[String],
    bars: &[Bars],
) -> Result<()> {
    let mut svg = String::new();
    let root = SVGBackend::with_string(&mut svg, (1000, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let stacks = bars.iter().map(|b| b.stack + 1).max().unwrap_or(1);
    let mut top: f64 = 0.0;
    for c in 0..categories.len() {
        for s in 0..stacks {
            let h: f64 = bars
                .iter()
                .filter(|b| b.stack == s)
                .map(|b| b.values.get(c).copied().unwrap_or(0.0).max(0.0))
                .sum();
            top = top.max(h);
        }
    }
    let n = categories.len().max(1) as f64;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(16)
        .x_label_area_size(56)
        .y_label_area_size(64)
        // Headroom above the tallest bar for the legend.
        .build_cartesian_2d(0.0..n, 0.0..(top * 1.3).max(1e-9))?;
    let names = categories.to_vec();
    let xfmt = move |x: &f64| {
        let i = x.floor() as usize;
        // Label once per category, at its centre.
        if (x - (i as f64 + 0.5)).abs() < 1e-6 {
            names.get(i).cloned().unwrap_or_default()
        } else {
            String::new()
        }
    };
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(2 * categories.len() + 1)
        .x_label_formatter(&xfmt)
        .y_desc(y_label)
        .draw()?;
    // Each category spans [c, c + 1): 10 % margin on both sides, stacks share the rest.
    let width = 0.8 / stacks as f64;
    for (i, b) in bars.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let rects: Vec<_> = b
            .values
            .iter()
            .enumerate()
            .map(|(c, &v)| {
                let below: f64 = bars[..i]
                    .iter()
                    .filter(|o| o.stack == b.stack)
                    .map(|o| o.values.get(c).copied().unwrap_or(0.0).max(0.0))
                    .sum();
                let x0 = c as f64 + 0.1 + width * b.stack as f64;
                Rectangle::new(
                    [(x0, below), (x0 + width * 0.92, below + v.max(0.0))],
                    color.filled(),
                )
            })
            .collect();
        chart
            .draw_series(rects)?
            .label(b.label.clone())
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], color.filled()));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    root.present()
        .with_context(|| format!("{}: cannot draw plot", path.display()))?;
    drop(chart);
    drop(root);
    crate::atomic::write(path, svg)
        .with_context(|| format!("{}: cannot write plot", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_read_as_sizes() {
        assert_eq!(human(100_000.0), "100 k");
        assert_eq!(human(1_000_000.0), "1 M");
        assert_eq!(human(14_000_000.0), "14 M");
        assert_eq!(human(2_500_000.0), "2.5 M");
        assert_eq!(human(0.01), "0.01");
        assert_eq!(human(316_227.766), "316 k");
        assert_eq!(human(0.0), "0");
        // Over decades only powers of ten are labelled.
        assert_eq!(log_label(5.0, 3.0), "100 k");
        assert_eq!(log_label(5.5, 3.0), "");
        assert_eq!(log_label(5.5, 0.5), "316 k");
    }
}
