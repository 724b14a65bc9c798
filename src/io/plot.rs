//! PNG line plots of run results (temperature histories, radial profiles, ...).
//!
//! [`write_png`] draws one [`LinePlot`] — a title, axis labels and any number of
//! labelled [`Series`] — with the `plotters` bitmap backend and writes it as a PNG.
//!
//! # Text and fonts
//!
//! Text is rendered with `plotters`' `ab_glyph` feature, which needs no system
//! font library: a TrueType font file is read at run time and registered once per
//! process. The file is `$FDEM_PLOT_FONT` if that variable is set, otherwise the
//! first of [`FONT_CANDIDATES`] that exists (DejaVu Sans comes from the Debian
//! package `fonts-dejavu-core`, installed by `scripts/setup.sh`). If no font can be
//! loaded, [`write_png`] fails with [`PlotError::NoFont`] and writes nothing: a plot
//! without tick labels or legend would be misleading.
//!
//! # Data
//!
//! Axis ranges cover all finite points of all series with a 5 % margin on each
//! side. Non-finite points (NaN, ±inf) are skipped, so a line joins the finite
//! points on either side of them. A zero range (a single point, or a constant
//! series) is widened to ±5 % of the value (±0.5 around zero). A plot with no
//! finite point at all — an empty series list included — is not an error: it is
//! drawn with axes from 0 to 1, its title and axis labels, and (if there are
//! series) the legend. A series with a single finite point is drawn as a dot.
//! The legend (white, framed) goes into the corner of the plotting area that
//! covers the fewest data.
//!
//! # Atomic output
//!
//! The image is rendered in memory, written and synced to `<path>.tmp.png` and then
//! renamed over `path`, so an interrupted or failed call never leaves a truncated
//! PNG at `path` (the temporary name ends in `.png` because the encoder chooses the
//! format from the extension). The output is always PNG, whatever `path`'s
//! extension. On failure the temporary file is removed.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use plotters::element::DashedPathElement;
use plotters::prelude::*;

/// One line of a plot.
#[derive(Debug, Clone, Copy)]
pub struct Series<'a> {
    /// Legend entry.
    pub label: &'a str,
    /// `(x, y)` points, joined in the given order; non-finite points are skipped.
    pub points: &'a [(f64, f64)],
    /// Draw the line dashed instead of solid.
    pub dashed: bool,
}

/// A line plot: title, axis labels and the series drawn in it.
#[derive(Debug, Clone)]
pub struct LinePlot<'a> {
    /// Title above the plot.
    pub title: &'a str,
    /// Label of the horizontal axis.
    pub x_label: &'a str,
    /// Label of the vertical axis.
    pub y_label: &'a str,
    /// Lines, drawn in order with distinct colours (the palette repeats after ten).
    pub series: Vec<Series<'a>>,
}

/// Errors of [`write_png`]. Every message names the output file.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// No usable TrueType font was found for the plot text.
    #[error(
        "{}: no usable TrueType font for plot text (tried {tried}); install fonts-dejavu-core \
         (scripts/setup.sh) or set FDEM_PLOT_FONT to a .ttf file",
        path.display()
    )]
    NoFont {
        /// Output file.
        path: PathBuf,
        /// Font files tried, with the reason each was rejected.
        tried: String,
    },
    /// The image size is outside the supported range.
    #[error(
        "{}: invalid image size {}x{} (each side must be {MIN_SIDE}..={MAX_SIDE} pixels)",
        path.display(), size.0, size.1
    )]
    InvalidSize {
        /// Output file.
        path: PathBuf,
        /// Requested size.
        size: (u32, u32),
    },
    /// `plotters` failed to draw or encode the image.
    #[error("{}: plotting failed while {what}: {cause}", path.display())]
    Draw {
        /// Output file.
        path: PathBuf,
        /// What was being done.
        what: &'static str,
        /// The `plotters` error message.
        cause: String,
    },
    /// An operating-system I/O operation failed.
    #[error("{}: {what}: {cause}", path.display())]
    Io {
        /// File concerned (the output file or its temporary file).
        path: PathBuf,
        /// What was being done.
        what: &'static str,
        /// The underlying error.
        cause: std::io::Error,
    },
}

/// Smallest accepted image side in pixels.
pub const MIN_SIDE: u32 = 200;
/// Largest accepted image side in pixels.
pub const MAX_SIDE: u32 = 8192;

/// Font files tried, in order, when `FDEM_PLOT_FONT` is not set.
pub const FONT_CANDIDATES: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf", // Debian, Ubuntu
    "/usr/share/fonts/TTF/DejaVuSans.ttf",             // Arch
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf", // Fedora
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",          // older Fedora, Alpine
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/truetype/freefont/FreeSans.ttf",
    "/System/Library/Fonts/Supplemental/Arial.ttf", // macOS
];

/// Font family name under which the font is registered with `plotters`.
const FAMILY: &str = "sans-serif";

/// Series colours (matplotlib's "tab10").
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Path of the font registered with `plotters`, once one was registered.
static FONT: Mutex<Option<PathBuf>> = Mutex::new(None);

/// Registers a font with `plotters` unless one already is. Returns a description
/// of the files tried on failure.
fn ensure_font() -> Result<(), String> {
    let mut font = FONT.lock().unwrap_or_else(|e| e.into_inner());
    if font.is_some() {
        return Ok(());
    }
    let candidates: Vec<PathBuf> = match std::env::var_os("FDEM_PLOT_FONT") {
        Some(p) if !p.is_empty() => vec![PathBuf::from(p)],
        _ => FONT_CANDIDATES.iter().map(PathBuf::from).collect(),
    };
    *font = Some(register_first_font(&candidates)?);
    Ok(())
}

/// Registers the first loadable font file of `candidates` as [`FAMILY`] and
/// returns its path, or describes why each file was rejected.
fn register_first_font(candidates: &[PathBuf]) -> Result<PathBuf, String> {
    let mut tried = Vec::new();
    for path in candidates {
        let bytes = match std::fs::read(path) {
            Ok(b) => b,
            Err(e) => {
                tried.push(format!("{}: {e}", path.display()));
                continue;
            }
        };
        // sfnt version tags: TrueType, OpenType/CFF, old Apple TrueType.
        let magic = bytes.get(..4);
        if ![&[0u8, 1, 0, 0][..], b"OTTO", b"true"]
            .iter()
            .any(|m| magic == Some(m))
        {
            tried.push(format!("{}: not a TrueType/OpenType font", path.display()));
            continue;
        }
        // `register_font` needs `'static` data; this happens once per process.
        let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
        if plotters::style::register_font(FAMILY, FontStyle::Normal, bytes).is_ok() {
            return Ok(path.clone());
        }
        tried.push(format!("{}: invalid font data", path.display()));
    }
    if tried.is_empty() {
        tried.push("no font files".to_string());
    }
    Err(tried.join("; "))
}

/// `<path>.tmp.png`: the temporary file renamed over `path`.
fn tmp_path(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".tmp.png");
    PathBuf::from(name)
}

/// Draws `plot` into a PNG file at `path` of `size` = (width, height) pixels,
/// atomically (see the module documentation). Each side must be within
/// [`MIN_SIDE`]`..=`[`MAX_SIDE`].
pub fn write_png(plot: &LinePlot, path: &Path, size: (u32, u32)) -> Result<(), PlotError> {
    let rgb = render_rgb(plot, path, size)?;
    let tmp = tmp_path(path);
    let result = save_png(&rgb, &tmp, path, size);
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Encodes `rgb` to `tmp`, syncs it and renames it to `path`.
fn save_png(rgb: &[u8], tmp: &Path, path: &Path, size: (u32, u32)) -> Result<(), PlotError> {
    let draw_err = |what, e: &dyn std::fmt::Display| PlotError::Draw {
        path: path.to_path_buf(),
        what,
        cause: e.to_string(),
    };
    {
        let mut backend = BitMapBackend::new(tmp, size);
        backend
            .blit_bitmap((0, 0), size, rgb)
            .map_err(|e| draw_err("copying the image", &e))?;
        backend
            .present()
            .map_err(|e| draw_err("writing the PNG file", &e))?;
    }
    let file = std::fs::File::open(tmp).map_err(|cause| PlotError::Io {
        path: tmp.to_path_buf(),
        what: "opening temporary PNG file",
        cause,
    })?;
    file.sync_all().map_err(|cause| PlotError::Io {
        path: tmp.to_path_buf(),
        what: "syncing temporary PNG file",
        cause,
    })?;
    std::fs::rename(tmp, path).map_err(|cause| PlotError::Io {
        path: path.to_path_buf(),
        what: "renaming PNG file into place",
        cause,
    })
}

/// Axis range `(lo, hi)` with `lo < hi`, both finite, covering `[min, max]` with a
/// 5 % margin; `None` input gives `(0, 1)`.
fn axis_range(bounds: Option<(f64, f64)>) -> (f64, f64) {
    let Some((min, max)) = bounds else {
        return (0.0, 1.0);
    };
    let mag = min.abs().max(max.abs());
    // Keep the span well above the float resolution of the values so that tick
    // computation stays meaningful; this also widens a zero range.
    let span = (max - min).max(mag * 1e-9);
    let (lo, hi) = if span > 0.0 {
        let pad = if max > min { 0.05 * span } else { 0.05 * mag };
        (min - pad, max + pad)
    } else {
        (min - 0.5, max + 0.5) // min == max == 0
    };
    if lo.is_finite() && hi.is_finite() && lo < hi {
        (lo, hi)
    } else if min < max && (max - min).is_finite() {
        (min, max) // the margin overflowed
    } else {
        // Values near ±f64::MAX: use a range that stays representable.
        (-f64::MAX / 2.0, f64::MAX / 2.0)
    }
}

/// Bounds `((xmin, xmax), (ymin, ymax))` of the finite points, if any.
fn data_bounds(series: &[Series]) -> Option<((f64, f64), (f64, f64))> {
    let mut b: Option<((f64, f64), (f64, f64))> = None;
    for &(x, y) in series.iter().flat_map(|s| s.points) {
        if !(x.is_finite() && y.is_finite()) {
            continue;
        }
        b = Some(match b {
            None => ((x, x), (y, y)),
            Some(((x0, x1), (y0, y1))) => ((x0.min(x), x1.max(x)), (y0.min(y), y1.max(y))),
        });
    }
    b
}

/// Tick label: plain for moderate magnitudes, scientific otherwise. Values below
/// `span * 1e-9` in magnitude (rounding noise of a zero tick on an axis of width
/// `span`) print as `0`.
fn tick_label(v: f64, span: f64) -> String {
    let v = if v.abs() <= span * 1e-9 { 0.0 } else { v };
    let a = v.abs();
    if a == 0.0 || (1e-3..1e5).contains(&a) {
        let s = format!("{v:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        if s == "-0" {
            "0".to_string()
        } else {
            s.to_string()
        }
    } else {
        format!("{v:.3e}")
            .replace(".000e", "e")
            .replace("00e", "e")
            .replace("0e", "e")
    }
}

/// Picks the legend corner covering the fewest data: points and samples along the
/// segments between them that fall into a legend-sized box in each corner.
/// `legend` is the legend's size as a fraction of the plotting area.
fn legend_corner(
    series: &[Series],
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
    legend: (f64, f64),
) -> SeriesLabelPosition {
    // Halved to keep differences of values near ±f64::MAX finite.
    let norm = |v: f64, lo: f64, hi: f64| (v / 2.0 - lo / 2.0) / (hi / 2.0 - lo / 2.0);
    let (w, h) = legend;
    let corners = [
        (SeriesLabelPosition::UpperRight, 1.0 - w, 1.0, 1.0 - h, 1.0),
        (SeriesLabelPosition::UpperLeft, 0.0, w, 1.0 - h, 1.0),
        (SeriesLabelPosition::LowerRight, 1.0 - w, 1.0, 0.0, h),
        (SeriesLabelPosition::LowerLeft, 0.0, w, 0.0, h),
    ];
    let mut counts = [0usize; 4];
    for s in series {
        let mut prev: Option<(f64, f64)> = None;
        for &(x, y) in s.points {
            if !(x.is_finite() && y.is_finite()) {
                continue;
            }
            let p = (norm(x, x0, x1), norm(y, y0, y1));
            let a = prev.unwrap_or(p);
            for k in 0..=8 {
                let t = f64::from(k) / 8.0;
                let (u, v) = (a.0 + t * (p.0 - a.0), a.1 + t * (p.1 - a.1));
                for (c, &(_, ul, uh, vl, vh)) in counts.iter_mut().zip(&corners) {
                    if (ul..=uh).contains(&u) && (vl..=vh).contains(&v) {
                        *c += 1;
                    }
                }
            }
            prev = Some(p);
        }
    }
    let best = (0..4).min_by_key(|&i| counts[i]).unwrap_or(0);
    corners[best].0.clone()
}

/// Renders `plot` to an RGB8 buffer (row-major, 3 bytes per pixel).
fn render_rgb(plot: &LinePlot, path: &Path, size: (u32, u32)) -> Result<Vec<u8>, PlotError> {
    let side_ok = |s: u32| (MIN_SIDE..=MAX_SIDE).contains(&s);
    if !(side_ok(size.0) && side_ok(size.1)) {
        return Err(PlotError::InvalidSize {
            path: path.to_path_buf(),
            size,
        });
    }
    ensure_font().map_err(|tried| PlotError::NoFont {
        path: path.to_path_buf(),
        tried,
    })?;
    let draw_err = |what, e: &dyn std::fmt::Display| PlotError::Draw {
        path: path.to_path_buf(),
        what,
        cause: e.to_string(),
    };

    let bounds = data_bounds(&plot.series);
    let (x0, x1) = axis_range(bounds.map(|b| b.0));
    let (y0, y1) = axis_range(bounds.map(|b| b.1));

    // Sizes scale with the image height (reference: 600 pixels), but text stays
    // readable in small images.
    let scale = (f64::from(size.1) / 600.0).max(0.8);
    let px = |v: f64| ((v * scale).round() as u32).max(1);
    let line_width = px(2.0);
    let legend_len = px(24.0);
    let label_px = px(14.0);

    // Approximate legend size relative to the plotting area, for placing it.
    let plot_w = f64::from(size.0) - f64::from(px(80.0) + 2 * px(12.0));
    let plot_h = f64::from(size.1) - f64::from(px(50.0) + px(30.0) + 2 * px(12.0));
    let max_chars = plot.series.iter().map(|s| s.label.chars().count()).max();
    let legend_w = f64::from(legend_len + 3 * px(10.0))
        + 0.6 * f64::from(label_px) * max_chars.unwrap_or(0) as f64;
    let legend_h = f64::from(2 * px(10.0)) + 1.5 * f64::from(label_px) * plot.series.len() as f64;
    let legend_rel = (
        (legend_w / plot_w.max(1.0)).min(1.0),
        (legend_h / plot_h.max(1.0)).min(1.0),
    );

    let mut buf = vec![0u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        root.fill(&WHITE)
            .map_err(|e| draw_err("filling the background", &e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(plot.title, (FAMILY, px(24.0)))
            .margin(px(12.0))
            .x_label_area_size(px(50.0))
            .y_label_area_size(px(80.0))
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| draw_err("laying out the chart", &e))?;
        chart
            .configure_mesh()
            .x_desc(plot.x_label)
            .y_desc(plot.y_label)
            .axis_desc_style((FAMILY, px(18.0)))
            .label_style((FAMILY, px(14.0)))
            .x_label_formatter(&|v| tick_label(*v, x1 - x0))
            .y_label_formatter(&|v| tick_label(*v, y1 - y0))
            .light_line_style(RGBColor(235, 235, 235))
            .bold_line_style(RGBColor(210, 210, 210))
            .draw()
            .map_err(|e| draw_err("drawing the axes", &e))?;

        for (i, s) in plot.series.iter().enumerate() {
            let color = PALETTE[i % PALETTE.len()];
            let style = color.stroke_width(line_width);
            let points = s
                .points
                .iter()
                .copied()
                .filter(|(x, y)| x.is_finite() && y.is_finite());
            if let (Some(p), None) = (points.clone().next(), points.clone().nth(1)) {
                // A lone point draws no line: mark it.
                chart
                    .draw_series(std::iter::once(Circle::new(p, px(4.0), style.filled())))
                    .map_err(|e| draw_err("drawing a series", &e))?;
            }
            let anno = if s.dashed {
                chart.draw_series(DashedLineSeries::new(points, px(8.0), px(5.0), style))
            } else {
                chart.draw_series(LineSeries::new(points, style))
            }
            .map_err(|e| draw_err("drawing a series", &e))?;
            let dashed = s.dashed;
            let len = legend_len as i32;
            anno.label(s.label).legend(move |(x, y)| {
                let pts = vec![(x, y), (x + len, y)];
                if dashed {
                    DashedPathElement::new(pts, len / 3, len / 6, style).into_dyn()
                } else {
                    PathElement::new(pts, style).into_dyn()
                }
            });
        }

        if !plot.series.is_empty() {
            chart
                .configure_series_labels()
                .position(legend_corner(&plot.series, (x0, x1), (y0, y1), legend_rel))
                .legend_area_size(legend_len + px(6.0))
                .label_font((FAMILY, label_px))
                .background_style(WHITE)
                .border_style(BLACK)
                .margin(px(10.0))
                .draw()
                .map_err(|e| draw_err("drawing the legend", &e))?;
        }
        root.present()
            .map_err(|e| draw_err("finishing the image", &e))?;
    }
    Ok(buf)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Width, height and file size of a PNG file after checking its signature and
    /// IHDR chunk.
    fn png_info(path: &Path) -> (u32, u32, usize) {
        let bytes = std::fs::read(path).unwrap();
        assert!(bytes.len() > 33, "file too short: {} bytes", bytes.len());
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
        assert_eq!(&bytes[8..12], &[0, 0, 0, 13], "IHDR length");
        assert_eq!(&bytes[12..16], b"IHDR");
        let be = |i: usize| u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap());
        (be(16), be(20), bytes.len())
    }

    fn three_series_plot<'a>(
        mean: &'a [(f64, f64)],
        min: &'a [(f64, f64)],
        max: &'a [(f64, f64)],
    ) -> LinePlot<'a> {
        LinePlot {
            title: "Particle temperature",
            x_label: "time [s]",
            y_label: "T [K]",
            series: vec![
                Series {
                    label: "mean",
                    points: mean,
                    dashed: false,
                },
                Series {
                    label: "min",
                    points: min,
                    dashed: true,
                },
                Series {
                    label: "max",
                    points: max,
                    dashed: true,
                },
            ],
        }
    }

    fn curve(f: impl Fn(f64) -> f64) -> Vec<(f64, f64)> {
        (0..=100)
            .map(|i| i as f64 * 0.1)
            .map(|t| (t, f(t)))
            .collect()
    }

    /// Number of distinct RGB colours in a buffer.
    fn distinct_colours(rgb: &[u8]) -> usize {
        let set: std::collections::HashSet<&[u8]> = rgb.chunks_exact(3).collect();
        set.len()
    }

    #[test]
    fn three_series_write_valid_png() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("temperature.png");
        let mean = curve(|t| 300.0 + 10.0 * t);
        let min = curve(|t| 300.0 + 6.0 * t);
        let mut max = curve(|t| 300.0 + 15.0 * t);
        max[50].1 = f64::NAN; // skipped
        max[51].0 = f64::INFINITY; // skipped
        let plot = three_series_plot(&mean, &min, &max);
        write_png(&plot, &path, (800, 600)).unwrap();

        let (w, h, len) = png_info(&path);
        assert_eq!((w, h), (800, 600));
        assert!(len > 5000, "PNG only {len} bytes");
        assert!(!tmp_path(&path).exists(), "temporary file left behind");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);

        // The rendered image: white background, the three series colours, and
        // anti-aliased text (many grey levels).
        let rgb = render_rgb(&plot, &path, (800, 600)).unwrap();
        assert!(distinct_colours(&rgb) > 20);
        for c in &PALETTE[..3] {
            let n = rgb
                .chunks_exact(3)
                .filter(|p| *p == [c.0, c.1, c.2])
                .count();
            assert!(n > 100, "colour {c:?} drawn on only {n} pixels");
        }
        let dark = rgb
            .chunks_exact(3)
            .filter(|p| p.iter().all(|&v| v < 64))
            .count();
        assert!(dark > 500, "too few dark (text/axis) pixels: {dark}");
    }

    #[test]
    fn rewrites_existing_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.png");
        std::fs::write(&path, b"old").unwrap();
        let pts = curve(|t| t * t);
        let plot = LinePlot {
            title: "T(r)",
            x_label: "r [m]",
            y_label: "T [K]",
            series: vec![Series {
                label: "t = 1 s",
                points: &pts,
                dashed: false,
            }],
        };
        write_png(&plot, &path, (640, 480)).unwrap();
        assert_eq!(png_info(&path).0, 640);
    }

    #[test]
    fn degenerate_data_do_not_panic() {
        let dir = tempfile::tempdir().unwrap();
        let one = [(1.0, 300.0)];
        let constant = curve(|_| 300.0);
        let zero = curve(|_| 0.0);
        let nearly = [(0.0, 300.0), (1.0, 300.0 + 1e-12)];
        let huge = [(-f64::MAX, f64::MAX), (f64::MAX, -f64::MAX)];
        let tiny = [(0.0, 1e-300), (1e-300, 2e-300)];
        let nan = [(f64::NAN, 1.0), (2.0, f64::NEG_INFINITY)];
        let cases: [(&str, &[(f64, f64)]); 8] = [
            ("one", &one),
            ("constant", &constant),
            ("zero", &zero),
            ("nearly", &nearly),
            ("huge", &huge),
            ("tiny", &tiny),
            ("nan", &nan),
            ("empty", &[]),
        ];
        for (name, points) in cases {
            let plot = LinePlot {
                title: name,
                x_label: "x",
                y_label: "y",
                series: vec![Series {
                    label: name,
                    points,
                    dashed: false,
                }],
            };
            let path = dir.path().join(format!("{name}.png"));
            write_png(&plot, &path, (400, 300)).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(png_info(&path).0, 400, "{name}");
        }
    }

    #[test]
    fn empty_series_list_gives_empty_plot() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("empty.png");
        let plot = LinePlot {
            title: "nothing yet",
            x_label: "time [s]",
            y_label: "T [K]",
            series: vec![],
        };
        write_png(&plot, &path, (400, 300)).unwrap();
        assert_eq!(png_info(&path).0, 400);
    }

    #[test]
    fn missing_directory_error_names_path() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("no_such_dir").join("plot.png");
        let pts = curve(|t| t);
        let plot = three_series_plot(&pts, &pts, &pts);
        let err = write_png(&plot, &path, (400, 300)).unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains(&path.display().to_string()),
            "error does not name the path: {msg}"
        );
        assert!(!path.exists() && !tmp_path(&path).exists());
    }

    #[test]
    fn invalid_size_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("plot.png");
        let plot = three_series_plot(&[], &[], &[]);
        for size in [(0, 300), (400, 10), (MAX_SIDE + 1, 300)] {
            let err = write_png(&plot, &path, size).unwrap_err();
            assert!(matches!(err, PlotError::InvalidSize { .. }), "{err}");
            assert!(err.to_string().contains("plot.png"));
        }
        assert!(!path.exists());
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick_label(0.0, 1.0), "0");
        assert_eq!(tick_label(-0.0, 1.0), "0");
        assert_eq!(tick_label(300.0, 100.0), "300");
        assert_eq!(tick_label(0.25, 1.0), "0.25");
        assert_eq!(tick_label(1.5e-7, 1e-6), "1.5e-7");
        assert_eq!(tick_label(2e6, 1e7), "2e6");
        assert_eq!(tick_label(1.25e-7, 1e-6), "1.25e-7");
        assert_eq!(tick_label(2.6e-23, 2e-7), "0");
    }

    #[test]
    fn axis_ranges_have_margin_and_nonzero_width() {
        assert_eq!(axis_range(None), (0.0, 1.0));
        let (lo, hi) = axis_range(Some((0.0, 10.0)));
        assert!((lo + 0.5).abs() < 1e-12 && (hi - 10.5).abs() < 1e-12);
        let (lo, hi) = axis_range(Some((300.0, 300.0)));
        assert!(lo < 300.0 && hi > 300.0 && hi - lo < 31.0);
        let (lo, hi) = axis_range(Some((0.0, 0.0)));
        assert!(lo < 0.0 && hi > 0.0);
        let (lo, hi) = axis_range(Some((-f64::MAX, f64::MAX)));
        assert!(lo.is_finite() && hi.is_finite() && lo < hi);
    }

    #[test]
    fn unusable_font_files_are_reported() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("missing.ttf");
        let text = dir.path().join("text.ttf");
        std::fs::write(&text, "not a font").unwrap();
        let err = register_first_font(&[missing.clone(), text.clone()]).unwrap_err();
        assert!(err.contains(&missing.display().to_string()), "{err}");
        assert!(err.contains(&text.display().to_string()), "{err}");
        assert!(err.contains("not a TrueType/OpenType font"), "{err}");
        let e = PlotError::NoFont {
            path: PathBuf::from("out/plot.png"),
            tried: err,
        };
        assert!(e
            .to_string()
            .starts_with("out/plot.png: no usable TrueType font"));
    }

    #[test]
    fn legend_avoids_data() {
        let rising = curve(|t| t); // fills lower left and upper right
        let s = |points| Series {
            label: "s",
            points,
            dashed: false,
        };
        let corner = legend_corner(&[s(&rising)], (0.0, 10.0), (0.0, 10.0), (0.3, 0.2));
        assert!(matches!(corner, SeriesLabelPosition::UpperLeft));
        let falling = curve(|t| 10.0 - t);
        let corner = legend_corner(&[s(&falling)], (0.0, 10.0), (0.0, 10.0), (0.3, 0.2));
        assert!(matches!(corner, SeriesLabelPosition::UpperRight));
        // Two points only: the segment between them counts.
        let two = [(0.0, 10.0), (10.0, 0.0)];
        let corner = legend_corner(&[s(&two)], (0.0, 10.0), (0.0, 10.0), (0.3, 0.2));
        assert!(matches!(corner, SeriesLabelPosition::UpperRight));
    }
}
