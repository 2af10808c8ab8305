//! Log–log charts as SVG, shared by the benchmark reports.
//!
//! plotters is built without a font backend (no system fonts needed), so it draws the frame, grid
//! and marks, and [`log_log_svg`] writes every text (title, axis names, tick labels, legend) as
//! plain SVG `<text>` placed by hand.

use plotters::coord::Shift;
use plotters::prelude::*;
use std::error::Error;

/// The chart a [`log_log_svg`] call draws into, with log axes in data units.
pub type LogChart<'a, 'b> =
    ChartContext<'a, SVGBackend<'b>, Cartesian2d<LogCoord<f64>, LogCoord<f64>>>;

/// What a log–log chart shows around its marks.
#[derive(Clone, Debug, PartialEq)]
pub struct LogLogSpec {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Title above the chart.
    pub title: String,
    /// Name of the horizontal axis.
    pub x_label: String,
    /// Name of the vertical axis.
    pub y_label: String,
    /// Data range of the horizontal axis (positive, low < high).
    pub x_range: (f64, f64),
    /// Data range of the vertical axis (positive, low < high).
    pub y_range: (f64, f64),
    /// Room right of the chart, for the legend.
    pub legend_width: u32,
}

/// The drawing state handed to the caller's closure: the chart, the whole image, and the texts.
pub struct Canvas<'a, 'b> {
    /// The chart, in data coordinates.
    pub chart: LogChart<'a, 'b>,
    /// The whole image, in pixels.
    pub root: DrawingArea<SVGBackend<'b>, Shift>,
    /// Pixel position of the chart's lower-left corner.
    pub lower_left: (i32, i32),
    /// Pixel position of the chart's upper-right corner.
    pub upper_right: (i32, i32),
    texts: Vec<String>,
}

impl Canvas<'_, '_> {
    /// Adds a text at pixel (x, y) with `anchor` start, middle or end (XML-escaped here).
    pub fn text(&mut self, x: i32, y: i32, anchor: &str, size: u32, body: &str) {
        self.texts.push(format!(
            "<text x=\"{x}\" y=\"{y}\" font-family=\"sans-serif\" font-size=\"{size}\" text-anchor=\"{anchor}\">{}</text>",
            escape(body)
        ));
    }

    /// Adds a legend entry right of the chart at pixel row `y`: a dot of `colour`, `name` beside
    /// it and, if given, a smaller `note` below.
    pub fn legend_dot(
        &mut self,
        y: i32,
        colour: RGBAColor,
        name: &str,
        note: Option<&str>,
    ) -> Result<(), Box<dyn Error>> {
        let x = self.upper_right.0;
        self.root
            .draw(&Circle::new((x + 24, y - 4), 7, colour.filled()))?;
        self.legend_text(y, name, note);
        Ok(())
    }

    /// Adds a legend entry right of the chart at pixel row `y`: a short line in `style`, `name`
    /// beside it and, if given, a smaller `note` below.
    pub fn legend_line(
        &mut self,
        y: i32,
        style: ShapeStyle,
        name: &str,
        note: Option<&str>,
    ) -> Result<(), Box<dyn Error>> {
        let x = self.upper_right.0;
        self.root.draw(&PathElement::new(
            vec![(x + 16, y - 4), (x + 34, y - 4)],
            style,
        ))?;
        self.legend_text(y, name, note);
        Ok(())
    }

    fn legend_text(&mut self, y: i32, name: &str, note: Option<&str>) {
        let x = self.upper_right.0 + 38;
        self.text(x, y, "start", 14, name);
        if let Some(note) = note {
            self.text(x, y + 17, "start", 11, note);
        }
    }

    /// Pixel position of a data point.
    pub fn pixel(&self, x: f64, y: f64) -> (i32, i32) {
        self.chart.backend_coord(&(x, y))
    }
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// Tick values 1, 2 and 5 times each power of ten within [lo, hi], with their leading digit.
fn ticks(lo: f64, hi: f64) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for p in lo.log10().floor() as i32..=hi.log10().ceil() as i32 {
        for k in [1.0, 2.0, 5.0] {
            // k·10^p in one rounding, so 2·10⁻² prints as 0.02.
            let t = if p >= 0 {
                k * 10f64.powi(p)
            } else {
                k / 10f64.powi(-p)
            };
            if t >= lo && t <= hi {
                out.push((t, k));
            }
        }
    }
    out
}

/// A horizontal tick label: plain decimals from 0.001 to 99999, else 1e±n / 2e±n.
fn x_tick_label(t: f64) -> String {
    if (1e-3..1e5).contains(&t) {
        format!("{t}")
    } else {
        exponent_label(t)
    }
}

fn exponent_label(t: f64) -> String {
    let p = t.log10().floor();
    let k = (t / 10f64.powf(p)).round();
    if k == 1.0 {
        format!("1e{p}")
    } else {
        format!("{k}e{p}")
    }
}

/// Draws a log–log chart: frame, grid lines at 1, 2 and 5 per decade horizontally and at every
/// decade vertically (also at 2 and 5 when the vertical range spans fewer than three decades),
/// tick labels, axis names and title; then `draw` adds the marks and the legend. Returns the SVG.
pub fn log_log_svg(
    spec: &LogLogSpec,
    draw: impl FnOnce(&mut Canvas<'_, '_>) -> Result<(), Box<dyn Error>>,
) -> Result<String, Box<dyn Error>> {
    let (x0, x1) = spec.x_range;
    let (y0, y1) = spec.y_range;
    for (lo, hi) in [spec.x_range, spec.y_range] {
        if !(lo > 0.0 && hi > lo && hi.is_finite()) {
            return Err(format!("log axis range {lo}..{hi} is not positive and increasing").into());
        }
    }
    let mut svg = String::new();
    let texts = {
        let root = SVGBackend::with_string(&mut svg, (spec.width, spec.height)).into_drawing_area();
        root.fill(&WHITE)?;
        let chart = ChartBuilder::on(&root)
            .margin_top(50)
            .margin_right(spec.legend_width)
            .margin_left(90)
            .margin_bottom(60)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
        let lower_left = chart.backend_coord(&(x0, y0));
        let upper_right = chart.backend_coord(&(x1, y1));
        let mut canvas = Canvas {
            chart,
            root: root.clone(),
            lower_left,
            upper_right,
            texts: Vec::new(),
        };
        let ((px0, py0), (px1, py1)) = (lower_left, upper_right);
        root.draw(&Rectangle::new(
            [(px0, py1), (px1, py0)],
            BLACK.stroke_width(1),
        ))?;
        let decades_only = y1 / y0 >= 1000.0;
        for (e, k) in ticks(y0, y1) {
            if decades_only && k != 1.0 {
                continue;
            }
            let (_, py) = canvas.pixel(x0, e);
            root.draw(&PathElement::new(
                vec![(px0, py), (px1, py)],
                BLACK.mix(0.12),
            ))?;
            canvas.text(px0 - 6, py + 4, "end", 12, &exponent_label(e));
        }
        for (t, _) in ticks(x0, x1) {
            let (px, _) = canvas.pixel(t, y0);
            root.draw(&PathElement::new(
                vec![(px, py0), (px, py1)],
                BLACK.mix(0.12),
            ))?;
            canvas.text(px, py0 + 18, "middle", 12, &x_tick_label(t));
        }
        canvas.text((px0 + px1) / 2, py0 + 42, "middle", 14, &spec.x_label);
        canvas.texts.push(format!(
            "<text x=\"24\" y=\"{y}\" font-family=\"sans-serif\" font-size=\"14\" text-anchor=\"middle\" transform=\"rotate(-90 24 {y})\">{}</text>",
            escape(&spec.y_label),
            y = (py0 + py1) / 2,
        ));
        canvas.text((spec.width / 2) as i32, 28, "middle", 18, &spec.title);
        draw(&mut canvas)?;
        root.present()?;
        canvas.texts
    };
    let close = svg.rfind("</svg>").ok_or("plotters wrote no closing tag")?;
    svg.insert_str(close, &(texts.join("\n") + "\n"));
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_one_two_five_per_decade() {
        let values = |lo, hi| {
            ticks(lo, hi)
                .into_iter()
                .map(|(t, _)| t)
                .collect::<Vec<_>>()
        };
        assert_eq!(values(0.015, 0.3), vec![0.02, 0.05, 0.1, 0.2]);
        assert_eq!(values(30.0, 120.0), vec![50.0, 100.0]);
        assert_eq!(x_tick_label(0.02), "0.02");
        assert_eq!(exponent_label(1e-7), "1e-7");
        assert_eq!(exponent_label(5e-3), "5e-3");
    }

    #[test]
    fn chart_has_texts_marks_and_refuses_bad_ranges() {
        let spec = LogLogSpec {
            width: 400,
            height: 300,
            title: "a < b".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            x_range: (0.01, 10.0),
            y_range: (1e-4, 1e-1),
            legend_width: 100,
        };
        let svg = log_log_svg(&spec, |c| {
            c.chart
                .draw_series(std::iter::once(Circle::new((1.0, 1e-2), 4, RED.filled())))?;
            c.legend_dot(60, RED.to_rgba(), "legend", Some("a note"))?;
            c.legend_line(100, BLACK.stroke_width(2), "a line", None)?;
            Ok(())
        })
        .unwrap();
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>\n"));
        assert!(svg.contains("a &lt; b") && svg.contains(">legend<") && svg.contains("<circle"));
        assert!(svg.contains(">a note<") && svg.contains(">a line<"));
        assert!(svg.contains(">0.01<") && svg.contains(">1e-3<"));
        let bad = LogLogSpec {
            x_range: (0.0, 1.0),
            ..spec
        };
        assert!(log_log_svg(&bad, |_| Ok(())).is_err());
    }
}
