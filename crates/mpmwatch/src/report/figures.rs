//! Figures of an analysis, each written as SVG and PNG:
//!
//! * `mi_lags`: MI against lag for every dither × residual pair, with the per-lag surrogate
//!   critical value (the paper's Figures 3, 8, 10, 16), one panel per pair;
//! * `ccf_lags`: the cross-correlation against lag with its ±z/√N limits (Figures 2, 9, 11, 17);
//! * `mi_matrix`: the MI matrix as a heat map, each cell shaded by the deciding statistic over
//!   its critical value and labelled with the norm of MI, the element's p-value and the verdict;
//! * `pair_<mv>_<cv>_mi` and `pair_<mv>_<cv>_ccf`: the same two plots for each pair alone.
//!
//! PNG text is drawn with DejaVu Sans embedded in the binary, so no system font is needed.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;

use mpmwatch_core::detect::{Cell, MatrixResult, Verdict};
use mpmwatch_core::info::Units;

/// Why a figure could not be written.
#[derive(Debug, thiserror::Error)]
pub enum FigureError {
    /// The output folder could not be created.
    #[error("cannot create {path}: {source}")]
    Dir {
        /// The folder.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// Drawing or encoding failed.
    #[error("cannot draw {path}: {message}")]
    Draw {
        /// The file.
        path: PathBuf,
        /// What the backend said.
        message: String,
    },
}

const FONT: &str = "sans-serif";

fn ensure_font() {
    static ONCE: OnceLock<()> = OnceLock::new();
    ONCE.get_or_init(|| {
        // The bytes are a valid TTF shipped by the `dejavu` crate; failure would be a build defect.
        plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular())
            .unwrap_or_else(|_| panic!("embedded DejaVu Sans is not a valid font"));
    });
}

fn draw_err(path: &Path, e: impl std::fmt::Debug) -> FigureError {
    FigureError::Draw { path: path.to_path_buf(), message: format!("{e:?}") }
}

/// Renders one figure to `dir/name.svg` and `dir/name.png` with the same drawing function.
macro_rules! svg_and_png {
    ($dir:expr, $name:expr, $size:expr, $draw:expr) => {{
        let svg = $dir.join(format!("{}.svg", $name));
        {
            let root = SVGBackend::new(&svg, $size).into_drawing_area();
            $draw(&root).map_err(|e| draw_err(&svg, e))?;
            root.present().map_err(|e| draw_err(&svg, e))?;
        }
        let png = $dir.join(format!("{}.png", $name));
        {
            let root = BitMapBackend::new(&png, $size).into_drawing_area();
            $draw(&root).map_err(|e| draw_err(&png, e))?;
            root.present().map_err(|e| draw_err(&png, e))?;
        }
        Ok::<[PathBuf; 2], FigureError>([svg, png])
    }};
}

type DrawResult<DB> = Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

/// Writes the three figures of a matrix into `dir` (created if missing) and returns the files.
pub fn write_matrix_figures(dir: &Path, m: &MatrixResult, units: Units) -> Result<Vec<PathBuf>, FigureError> {
    ensure_font();
    std::fs::create_dir_all(dir).map_err(|source| FigureError::Dir { path: dir.to_path_buf(), source })?;
    let rows = m.residuals.len() as u32;
    let cols = m.dithers.len() as u32;
    let panel = ((cols * 300 + 20).max(640), rows * 220 + 40);
    let mut files = Vec::new();
    files.extend(svg_and_png!(dir, "mi_lags", panel, |root| draw_grid(root, m, units, Panel::Mi))?);
    files.extend(svg_and_png!(dir, "ccf_lags", panel, |root| draw_grid(root, m, units, Panel::Ccf))?);
    let heat = ((cols * 150 + 160).max(520), rows * 90 + 100);
    files.extend(svg_and_png!(dir, "mi_matrix", heat, |root| draw_heatmap(root, m, units))?);
    for c in &m.cells {
        let (mv, cv) = (&m.dithers[c.mv], &m.residuals[c.cv]);
        let stem = format!("pair_{}_{}", file_safe(mv), file_safe(cv));
        files.extend(svg_and_png!(dir, format!("{stem}_mi"), (560, 360), |root: &DrawingArea<_, Shift>| {
            root.fill(&WHITE)?;
            draw_mi_panel(root, c, mv, cv, units)
        })?);
        files.extend(svg_and_png!(dir, format!("{stem}_ccf"), (560, 360), |root: &DrawingArea<
            _,
            Shift,
        >| {
            root.fill(&WHITE)?;
            draw_ccf_panel(root, c, mv, cv)
        })?);
    }
    Ok(files)
}

/// A signal name made safe for a file name.
fn file_safe(name: &str) -> String {
    name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' { c } else { '_' }).collect()
}

#[derive(Clone, Copy)]
enum Panel {
    Mi,
    Ccf,
}

fn draw_grid<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    m: &MatrixResult,
    units: Units,
    what: Panel,
) -> DrawResult<DB> {
    root.fill(&WHITE)?;
    let title = match what {
        Panel::Mi => {
            format!("MI against lag, surrogate critical value (z = {}, {} surrogates)", m.z, m.surrogates)
        }
        Panel::Ccf => {
            "Cross-correlation against lag, family-wise 5 % limits over the lags (Bonferroni)".to_string()
        }
    };
    let (top, body) = root.split_vertically(30);
    top.draw(&Text::new(title, (10, 8), (FONT, 16).into_font()))?;
    let panels = body.split_evenly((m.residuals.len(), m.dithers.len()));
    for (k, area) in panels.iter().enumerate() {
        let (j, i) = (k / m.dithers.len(), k % m.dithers.len());
        match m.cell(i, j) {
            Some(c) => match what {
                Panel::Mi => draw_mi_panel(area, c, &m.dithers[i], &m.residuals[j], units)?,
                Panel::Ccf => draw_ccf_panel(area, c, &m.dithers[i], &m.residuals[j])?,
            },
            None => {
                area.draw(&Text::new(
                    format!("{} not excited", m.dithers[i]),
                    (20, 40),
                    (FONT, 13).into_font(),
                ))?;
            }
        }
    }
    Ok(())
}

fn bounds(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    let pad = ((hi - lo) * 0.08).max(1e-6);
    (lo - pad, hi + pad)
}

fn draw_mi_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    c: &Cell,
    mv: &str,
    cv: &str,
    units: Units,
) -> DrawResult<DB> {
    let t = &c.pairwise;
    let u = |v: f64| units.from_nats(v);
    let (y0, y1) = bounds(t.profile.iter().chain(&t.lag_critical).map(|&v| u(v)).chain([0.0]));
    let (x0, x1) = (*t.lags.first().unwrap_or(&0) as f64 - 0.5, *t.lags.last().unwrap_or(&1) as f64 + 0.5);
    let colour = if c.significant { RED } else { BLUE };
    let mut chart = ChartBuilder::on(area)
        .caption(format!("{mv} → {cv}"), (FONT, 13))
        .margin(6)
        .x_label_area_size(32)
        .y_label_area_size(48)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    let unit = if units == Units::Bits { "bits" } else { "nats" };
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("lag")
        .x_label_formatter(&|v| if (v - v.round()).abs() < 1e-9 { format!("{v:.0}") } else { String::new() })
        .y_desc(format!("MI ({unit})"))
        .label_style((FONT, 10))
        .axis_desc_style((FONT, 11))
        .draw()?;
    chart
        .draw_series(LineSeries::new(
            t.lags.iter().zip(&t.lag_critical).map(|(&l, &v)| (l as f64, u(v))),
            BLACK.stroke_width(1),
        ))?
        .label("critical value")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 14, y)], BLACK));
    chart
        .draw_series(LineSeries::new(t.lags.iter().zip(&t.profile).map(|(&l, &v)| (l as f64, u(v))), colour))?
        .label("MI")
        .legend(move |(x, y)| PathElement::new([(x, y), (x + 14, y)], colour));
    chart.draw_series(
        t.lags.iter().zip(&t.profile).map(|(&l, &v)| Circle::new((l as f64, u(v)), 3, colour.filled())),
    )?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font((FONT, 10))
        .draw()?;
    Ok(())
}

fn draw_ccf_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    c: &Cell,
    mv: &str,
    cv: &str,
) -> DrawResult<DB> {
    let b = &c.ccf;
    let reach = b.values.iter().fold(b.limit, |a, v| a.max(v.abs())) * 1.15;
    let (x0, x1) = (*b.lags.first().unwrap_or(&0) as f64 - 0.5, *b.lags.last().unwrap_or(&1) as f64 + 0.5);
    let colour = if b.significant { RED } else { BLUE };
    let mut chart = ChartBuilder::on(area)
        .caption(format!("{mv} → {cv}"), (FONT, 13))
        .margin(6)
        .x_label_area_size(32)
        .y_label_area_size(48)
        .build_cartesian_2d(x0..x1, -reach..reach)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("lag")
        .x_label_formatter(&|v| if (v - v.round()).abs() < 1e-9 { format!("{v:.0}") } else { String::new() })
        .y_desc("CCF")
        .label_style((FONT, 10))
        .axis_desc_style((FONT, 11))
        .draw()?;
    for lim in [b.limit, -b.limit] {
        chart.draw_series(LineSeries::new([(x0, lim), (x1, lim)], BLACK.stroke_width(1)))?;
    }
    for (&l, &v) in b.lags.iter().zip(&b.values) {
        chart.draw_series(LineSeries::new([(l as f64, 0.0), (l as f64, v)], colour))?;
    }
    chart.draw_series(
        b.lags.iter().zip(&b.values).map(|(&l, &v)| Circle::new((l as f64, v), 3, colour.filled())),
    )?;
    Ok(())
}

fn draw_heatmap<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    m: &MatrixResult,
    units: Units,
) -> DrawResult<DB> {
    root.fill(&WHITE)?;
    let unit = if units == Units::Bits { "bits" } else { "nats" };
    root.draw(&Text::new(
        format!("MI matrix: norm of MI ({unit}) / critical value; zero below it"),
        (10, 8),
        (FONT, 14).into_font(),
    ))?;
    let (left, top, w, h) = (120i32, 70i32, 150i32, 90i32);
    for (i, name) in m.dithers.iter().enumerate() {
        root.draw(&Text::new(name.clone(), (left + i as i32 * w + 10, top - 22), (FONT, 13).into_font()))?;
    }
    for (j, name) in m.residuals.iter().enumerate() {
        root.draw(&Text::new(name.clone(), (10, top + j as i32 * h + h / 2 - 6), (FONT, 13).into_font()))?;
        for i in 0..m.dithers.len() {
            let (x, y) = (left + i as i32 * w, top + j as i32 * h);
            let cell = m.cell(i, j);
            let ratio = cell.map_or(0.0, |c| (c.decision.value / c.decision.critical).max(0.0));
            let fill = match cell {
                None => RGBColor(220, 220, 220),
                Some(c) if c.significant => {
                    let s = ((ratio - 1.0) / 4.0).clamp(0.0, 1.0);
                    RGBColor(255, (200.0 - 150.0 * s) as u8, (160.0 - 140.0 * s) as u8)
                }
                Some(_) => RGBColor(255, 255, (255.0 - 60.0 * ratio.min(1.0)) as u8),
            };
            root.draw(&Rectangle::new([(x, y), (x + w - 4, y + h - 4)], fill.filled()))?;
            root.draw(&Rectangle::new([(x, y), (x + w - 4, y + h - 4)], RGBColor(160, 160, 160)))?;
            let lines = match cell {
                None => vec!["not excited".to_string()],
                Some(c) => {
                    let verdict =
                        m.channels.iter().find(|ch| ch.mv_index == i && ch.cv_index == j).map_or("", |ch| {
                            match ch.verdict {
                                Verdict::Mismatch => "MISMATCH",
                                Verdict::Clean => "clean",
                                Verdict::ImplicatedByFeedback => "via feedback",
                            }
                        });
                    vec![
                        format!("{:.4}, p = {:.1e}", units.from_nats(c.pairwise.norm), c.decision.p_value),
                        verdict.to_string(),
                    ]
                }
            };
            for (k, line) in lines.iter().enumerate() {
                root.draw(&Text::new(line.clone(), (x + 8, y + 20 + 22 * k as i32), (FONT, 12).into_font()))?;
            }
        }
    }
    Ok(())
}

/// One named series of (x, y) points, with an optional ± band (e.g. one standard deviation).
#[derive(Debug, Clone)]
pub struct XySeries {
    /// Legend label.
    pub label: String,
    /// Points.
    pub points: Vec<(f64, f64)>,
    /// Half-widths of an error bar at each point, if any.
    pub error: Option<Vec<f64>>,
    /// A marker at every point (a few points of a study); off for time series, where a marker
    /// per sample hides the signal.
    pub markers: bool,
    /// Drawn dashed (e.g. the nominal simulation under the recorded and corrected outputs).
    pub dashed: bool,
    /// Line colour (RGB); `None` takes the palette's next.
    pub colour: Option<(u8, u8, u8)>,
    /// Line width in pixels.
    pub width: u32,
}

impl XySeries {
    /// A study's series: a line through markers.
    pub fn points(label: impl Into<String>, points: Vec<(f64, f64)>, error: Option<Vec<f64>>) -> Self {
        Self { label: label.into(), points, error, markers: true, dashed: false, colour: None, width: 2 }
    }

    /// A time series: a plain line, dashed or not, of a given colour and width.
    pub fn line(
        label: impl Into<String>,
        points: Vec<(f64, f64)>,
        dashed: bool,
        colour: (u8, u8, u8),
        width: u32,
    ) -> Self {
        Self { label: label.into(), points, error: None, markers: false, dashed, colour: Some(colour), width }
    }
}

/// A simple x–y chart (lines, markers where asked, optional error bars), as SVG and PNG.
pub fn write_xy_chart(
    dir: &Path,
    name: &str,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[XySeries],
) -> Result<Vec<PathBuf>, FigureError> {
    ensure_font();
    std::fs::create_dir_all(dir).map_err(|source| FigureError::Dir { path: dir.to_path_buf(), source })?;
    let files = svg_and_png!(dir, name, (720, 420), |root| draw_xy(root, title, x_label, y_label, series))?;
    Ok(files.to_vec())
}

const PALETTE: [RGBColor; 4] =
    [RGBColor(31, 119, 180), RGBColor(214, 39, 40), RGBColor(44, 160, 44), RGBColor(148, 103, 189)];

fn draw_xy<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[XySeries],
) -> DrawResult<DB> {
    root.fill(&WHITE)?;
    let xs = series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
    let (x0, x1) = bounds(xs);
    let (y0, y1) = y_bounds(series);
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, 16))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .label_style((FONT, 11))
        .axis_desc_style((FONT, 12))
        .draw()?;
    for (k, s) in series.iter().enumerate() {
        let colour = s.colour.map_or(PALETTE[k % PALETTE.len()], |(r, g, b)| RGBColor(r, g, b));
        let width = s.width;
        let legend =
            move |(x, y): (i32, i32)| PathElement::new([(x, y), (x + 18, y)], colour.stroke_width(width));
        if s.dashed {
            chart
                .draw_series(DashedLineSeries::new(
                    s.points.iter().copied(),
                    6,
                    4,
                    colour.stroke_width(width),
                ))?
                .label(s.label.clone())
                .legend(legend);
        } else {
            chart
                .draw_series(LineSeries::new(s.points.iter().copied(), colour.stroke_width(width)))?
                .label(s.label.clone())
                .legend(legend);
        }
        if s.markers {
            chart.draw_series(s.points.iter().map(|&p| Circle::new(p, 4, colour.filled())))?;
        }
        if let Some(err) = &s.error {
            for (p, e) in s.points.iter().zip(err) {
                chart.draw_series(LineSeries::new([(p.0, p.1 - e), (p.0, p.1 + e)], colour))?;
            }
        }
    }
    chart
        .configure_series_labels()
        .position(emptiest_corner(series, (x0, x1), (y0, y1)))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font((FONT, 12))
        .draw()?;
    Ok(())
}

/// The y axis of an x–y chart: from zero when a series is a study's points (markers), so that
/// sizes compare by eye; the signals' own range, padded, when every series is a line, since a
/// level far from zero (a temperature at 32 °C, a tank at 9 V) would otherwise draw flat.
fn y_bounds(series: &[XySeries]) -> (f64, f64) {
    let ys = series.iter().flat_map(|s| {
        s.points.iter().enumerate().flat_map(move |(k, p)| {
            let e = s.error.as_ref().map_or(0.0, |e| e[k]);
            [p.1 - e, p.1 + e]
        })
    });
    let zero = series.iter().any(|s| s.markers).then_some(0.0);
    bounds(ys.chain(zero))
}

/// The corner of the plot whose box (45 % of the width, 35 % of the height) holds the fewest
/// points, for the legend: a fixed corner hides the data of every chart whose lines run
/// through it. Ties go to the upper right.
fn emptiest_corner(series: &[XySeries], (x0, x1): (f64, f64), (y0, y1): (f64, f64)) -> SeriesLabelPosition {
    let (w, h) = (0.45 * (x1 - x0), 0.35 * (y1 - y0));
    let corners = [
        (SeriesLabelPosition::UpperRight, x1 - w..=x1, y1 - h..=y1),
        (SeriesLabelPosition::UpperLeft, x0..=x0 + w, y1 - h..=y1),
        (SeriesLabelPosition::LowerRight, x1 - w..=x1, y0..=y0 + h),
        (SeriesLabelPosition::LowerLeft, x0..=x0 + w, y0..=y0 + h),
    ];
    let inside = |xs: &std::ops::RangeInclusive<f64>, ys: &std::ops::RangeInclusive<f64>| {
        series.iter().flat_map(|s| &s.points).filter(|p| xs.contains(&p.0) && ys.contains(&p.1)).count()
    };
    corners
        .into_iter()
        .map(|(pos, xs, ys)| (inside(&xs, &ys), pos))
        .min_by_key(|(n, _)| *n)
        .map_or(SeriesLabelPosition::UpperRight, |(_, pos)| pos)
}

/// One item of a before → after chart: a label, the value before and after, and whether the
/// item counts as a success (a triangle) or not (a cross).
#[derive(Debug, Clone)]
pub struct BeforeAfter {
    /// Short label under the item (e.g. `c09`).
    pub label: String,
    /// Value before.
    pub before: f64,
    /// Value after.
    pub after: f64,
    /// Drawn as a triangle when true, a cross when false.
    pub success: bool,
}

/// A before → after chart, as SVG and PNG: one arrow per item from its value before (grey dot)
/// to its value after (green when it rose, red when it fell; a triangle for a success, a cross
/// otherwise). Used for the casebook's held-out FIT per case, where a table of 28 pairs of numbers
/// hides which cases gained and which lost.
pub fn write_before_after_chart(
    dir: &Path,
    name: &str,
    title: &str,
    y_label: &str,
    items: &[BeforeAfter],
) -> Result<Vec<PathBuf>, FigureError> {
    ensure_font();
    std::fs::create_dir_all(dir).map_err(|source| FigureError::Dir { path: dir.to_path_buf(), source })?;
    let width = (items.len() as u32 * 28 + 140).max(520);
    let files = svg_and_png!(dir, name, (width, 420), |root| draw_before_after(root, title, y_label, items))?;
    Ok(files.to_vec())
}

fn draw_before_after<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    y_label: &str,
    items: &[BeforeAfter],
) -> DrawResult<DB> {
    root.fill(&WHITE)?;
    let (y0, y1) =
        bounds(items.iter().flat_map(|i| [i.before, i.after]).filter(|v| v.is_finite()).chain([0.0]));
    let n = items.len().max(1);
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, 16))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(-0.5..(n as f64 - 0.5), y0..y1)?;
    let labels: Vec<String> = items.iter().map(|i| i.label.clone()).collect();
    chart
        .configure_mesh()
        .x_labels(n)
        .x_label_formatter(&|x| {
            let k = x.round();
            if (x - k).abs() < 1e-6 && k >= 0.0 {
                labels.get(k as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        })
        .y_desc(y_label)
        .label_style((FONT, 10))
        .axis_desc_style((FONT, 12))
        .draw()?;
    let grey = RGBColor(150, 150, 150);
    let (up, down) = (RGBColor(44, 160, 44), RGBColor(214, 39, 40));
    for (k, it) in items.iter().enumerate() {
        if !(it.before.is_finite() && it.after.is_finite()) {
            continue;
        }
        let x = k as f64;
        let colour = if it.after >= it.before { up } else { down };
        chart.draw_series(LineSeries::new([(x, it.before), (x, it.after)], colour.stroke_width(2)))?;
        chart.draw_series([Circle::new((x, it.before), 4, grey.filled())])?;
        if it.success {
            chart.draw_series([TriangleMarker::new((x, it.after), 6, colour.filled())])?;
        } else {
            chart.draw_series([Cross::new((x, it.after), 6, colour.stroke_width(2))])?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod before_after_tests {
    use super::*;

    #[test]
    fn writes_both_files_with_text() {
        let dir = std::env::temp_dir().join(format!("mpmwatch-ba-{}", std::process::id()));
        let items = vec![
            BeforeAfter { label: "c01".into(), before: 10.0, after: 30.0, success: true },
            BeforeAfter { label: "c02".into(), before: 20.0, after: 5.0, success: false },
            BeforeAfter { label: "c03".into(), before: f64::NAN, after: 1.0, success: true },
        ];
        let files = write_before_after_chart(&dir, "ba", "held-out FIT", "FIT [%]", &items).unwrap();
        let svg = std::fs::read_to_string(&files[0]).unwrap();
        assert!(svg.contains("c02") && svg.contains("held-out FIT"), "labels missing from the SVG");
        assert!(std::fs::metadata(&files[1]).unwrap().len() > 1000, "PNG suspiciously small");
        std::fs::remove_dir_all(&dir).ok();
    }
}

#[cfg(test)]
mod xy_chart_tests {
    use super::*;

    /// Signals between 32 and 35 fill the axis (padded by 8 % of their span, 0.24 each side);
    /// the same values as a study's points keep zero on it.
    #[test]
    fn a_signal_fills_its_axis_and_a_study_starts_at_zero() {
        let pts: Vec<(f64, f64)> = (0..=3).map(|k| (k as f64, 32.0 + k as f64)).collect();
        let (lo, hi) = y_bounds(&[XySeries::line("T", pts.clone(), false, (0, 0, 0), 1)]);
        assert!((lo - 31.76).abs() < 1e-9 && (hi - 35.24).abs() < 1e-9, "{lo} {hi}");
        let (lo, hi) = y_bounds(&[XySeries::points("rate", pts, None)]);
        assert!(lo < 0.0 && lo > -3.0 && hi > 35.0, "{lo} {hi}");
    }

    /// A line rising from the lower left to the upper right leaves the other two corners empty;
    /// of those, the upper left comes first. A line along the top leaves both lower corners.
    #[test]
    fn the_legend_goes_where_the_lines_are_not() {
        let rising =
            XySeries::line("a", (0..=10).map(|k| (k as f64, k as f64)).collect(), false, (0, 0, 0), 1);
        let pos = emptiest_corner(&[rising], (0.0, 10.0), (0.0, 10.0));
        assert!(matches!(pos, SeriesLabelPosition::UpperLeft), "{pos:?}");
        let top = XySeries::line("b", (0..=10).map(|k| (k as f64, 9.5)).collect(), false, (0, 0, 0), 1);
        let pos = emptiest_corner(&[top], (0.0, 10.0), (0.0, 10.0));
        assert!(matches!(pos, SeriesLabelPosition::LowerRight), "{pos:?}");
    }
}
