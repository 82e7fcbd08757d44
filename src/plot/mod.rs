//! Pictures: rendered spheres, the paper's Figures 4–7, and the plots a fit needs.
//!
//! Everything is drawn with plotters into an SVG document in memory; a PNG is that document
//! rendered by resvg at the picture's size in pixels. Text uses the bundled DejaVu Sans
//! both for plotters' layout (registered once through its ab_glyph support) and for resvg
//! (the only font it knows), so no system fonts or fontconfig are needed.
//!
//! A picture is a value implementing `Picture`: its data are computed when it is built
//! (so tests can check the data the picture shows), and `Picture::draw` only draws.
//! `write_picture` writes a file, `svg_string`, `png_bytes` and `rgb_buffer` render
//! in memory.

pub(crate) mod contour;
pub(crate) mod design;
pub(crate) mod figures;
pub(crate) mod fit;
pub(crate) mod hemisphere;
pub(crate) mod legend;
pub(crate) mod marks;
pub(crate) mod overview;
pub(crate) mod sphere;
pub(crate) mod stroke;
pub(crate) mod svg;
pub(crate) mod ticks;
pub(crate) mod xy;

pub use fit::{key_svg_of_outcome, png_of_outcome, svg_of_outcome};

use crate::error::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{FontDesc, FontStyle};
use resvg::{tiny_skia, usvg};
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

/// The font family every picture uses.
pub(crate) const FONT: &str = "sans-serif";

pub(crate) static FONT_BYTES: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Register the bundled font under [`FONT`] (once per process).
pub(crate) fn ensure_font() -> Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(Error::Plot {
            path: PathBuf::from("assets/fonts/DejaVuSans.ttf"),
            message: "the bundled font could not be loaded".into(),
        })
    }
}

/// The font at `size` pixels.
pub(crate) fn font(size: f64) -> FontDesc<'static> {
    (FONT, size).into_font()
}

/// Error type of drawing on a backend `DB`.
pub(crate) type DrawError<DB> = DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>;

/// A picture that can be drawn on any plotters backend.
pub(crate) trait Picture {
    /// Size in pixels (width, height).
    fn size(&self) -> (u32, u32);

    /// Draw on `root` (already filled white, of [`Picture::size`]); curves go through
    /// `stroke::Canvas` at sub-pixel positions.
    fn draw<DB: stroke::Canvas>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawError<DB>>;
}

/// Output format, chosen by the file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Format {
    /// `.png`: the picture's SVG rendered by resvg at its pixel size, 8-bit RGB.
    Png,
    /// `.svg`: the SVG document as drawn, text as text, bitmaps embedded as data URLs.
    Svg,
}

impl Format {
    /// The format of `path` by its extension (`.png` or `.svg`, any case).
    pub(crate) fn of(path: &Path) -> Result<Format> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("png") => Ok(Format::Png),
            Some("svg") => Ok(Format::Svg),
            _ => Err(Error::Usage(format!(
                "{}: the output file must end in .png or .svg",
                crate::io::shown(path)
            ))),
        }
    }
}

fn plot_error<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> Error + '_ {
    move |e| Error::Plot {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// Write `pic` to `path` as PNG or SVG (by extension), creating the parent folder if
/// needed. The picture is rendered in memory and written with
/// `crate::io::write_atomic`: a failure (a full disk) leaves no empty or cut file and any
/// old picture intact.
pub(crate) fn write_picture<P: Picture>(pic: &P, path: &Path) -> Result<()> {
    let format = Format::of(path)?;
    let svg = svg_string(pic).map_err(named(path))?;
    write_rendered(&svg, pic.size(), format, path)
}

/// Write `pic` as `dir/stem.png` and `dir/stem.svg` (drawn once, the PNG rendered from the
/// SVG), each as [`write_picture`] does; returns both paths.
pub(crate) fn write_png_svg<P: Picture>(pic: &P, dir: &Path, stem: &str) -> Result<Vec<PathBuf>> {
    let paths = vec![
        dir.join(format!("{stem}.png")),
        dir.join(format!("{stem}.svg")),
    ];
    let svg = svg_string(pic).map_err(named(&paths[0]))?;
    let size = pic.size();
    write_rendered(&svg, size, Format::Png, &paths[0])?;
    write_rendered(&svg, size, Format::Svg, &paths[1])?;
    Ok(paths)
}

/// A picture error renamed after the file it was meant for.
fn named(path: &Path) -> impl Fn(Error) -> Error + '_ {
    move |e| match e {
        Error::Plot { message, .. } => Error::Plot {
            path: path.to_path_buf(),
            message,
        },
        other => other,
    }
}

/// Write the SVG document `svg` of a picture of `size` pixels to `path` in `format`,
/// atomically, creating the parent folder if needed.
fn write_rendered(svg: &str, size: (u32, u32), format: Format, path: &Path) -> Result<()> {
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|source| Error::File {
            path: parent.to_path_buf(),
            message: format!("cannot create the folder: {}", source.kind()),
        })?;
    }
    let bytes = match format {
        Format::Png => svg_to_png(svg, size).map_err(named(path))?,
        Format::Svg => svg.as_bytes().to_vec(),
    };
    crate::io::write_bytes(path, &bytes)
}

/// Render `pic` to a PNG file's bytes in memory: its SVG document ([`svg_string`])
/// rendered at [`Picture::size`] pixels, 8-bit RGB.
pub(crate) fn png_bytes<P: Picture>(pic: &P) -> Result<Vec<u8>> {
    svg_to_png(&svg_string(pic)?, pic.size())
}

/// The SVG document `svg` rendered as [`svg_to_rgb`] does, as a PNG file's bytes (8-bit
/// RGB).
fn svg_to_png(svg: &str, (w, h): (u32, u32)) -> Result<Vec<u8>> {
    use image::ImageEncoder;
    let rgb = svg_to_rgb(svg, (w, h))?;
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(&rgb, w, h, image::ColorType::Rgb8)
        .map_err(plot_error(Path::new("<png in memory>")))?;
    Ok(out)
}

/// Render `pic` to an SVG document in memory.
pub(crate) fn svg_string<P: Picture>(pic: &P) -> Result<String> {
    ensure_font()?;
    let mut out = String::new();
    let here = Path::new("<svg in memory>");
    let elements = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
    {
        let root = svg::SvgCanvas::new(&mut out, pic.size(), elements.clone()).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error(here))?;
        pic.draw(&root).map_err(plot_error(here))?;
        root.present().map_err(plot_error(here))?;
    }
    let out = svg::SvgCanvas::finish(&out, &elements.borrow());
    // plotters-svg 0.3.7 labels embedded bitmaps "data:png"; viewers need the MIME type.
    Ok(out.replace("href=\"data:png;base64,", "href=\"data:image/png;base64,"))
}

/// Render `pic` to an RGB buffer in memory (row-major, 3 bytes per pixel, top row first),
/// exactly the pixels of [`png_bytes`].
#[cfg(test)]
pub(crate) fn rgb_buffer<P: Picture>(pic: &P) -> Result<Vec<u8>> {
    svg_to_rgb(&svg_string(pic)?, pic.size())
}

/// The SVG document `svg` rendered by resvg (anti-aliased) onto a white bitmap of `w` × `h`
/// pixels, its view box stretched to fill it: RGB, row-major, top row first. Text is set in
/// the bundled font (the only one known, also under every generic family name); images
/// embedded as data URLs are drawn, and no file or other address is ever read.
pub(crate) fn svg_to_rgb(svg: &str, (w, h): (u32, u32)) -> Result<Vec<u8>> {
    let here = Path::new("<png in memory>");
    let options = usvg::Options {
        font_family: FONT_FAMILY.to_string(),
        fontdb: font_database(),
        image_href_resolver: usvg::ImageHrefResolver {
            resolve_data: usvg::ImageHrefResolver::default_data_resolver(),
            resolve_string: Box::new(|_, _| None),
        },
        ..usvg::Options::default()
    };
    let tree = usvg::Tree::from_str(svg, &options).map_err(plot_error(here))?;
    let mut pixmap = tiny_skia::Pixmap::new(w, h).ok_or_else(|| {
        plot_error(here)(format!(
            "a {w} × {h} picture cannot be drawn (empty or too large)"
        ))
    })?;
    pixmap.fill(tiny_skia::Color::WHITE);
    let view = tree.size();
    let fit = tiny_skia::Transform::from_scale(w as f32 / view.width(), h as f32 / view.height());
    resvg::render(&tree, fit, &mut pixmap.as_mut());
    // Every pixel is opaque (white below everything), so the premultiplied colour is the
    // colour itself.
    Ok(pixmap
        .data()
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect())
}

/// The family name of the bundled font.
const FONT_FAMILY: &str = "DejaVu Sans";

/// resvg's font database: the bundled font alone, also under every generic family name
/// (plotters writes `font-family="sans-serif"`). Built once per process.
fn font_database() -> Arc<usvg::fontdb::Database> {
    static DB: OnceLock<Arc<usvg::fontdb::Database>> = OnceLock::new();
    DB.get_or_init(|| {
        let mut db = usvg::fontdb::Database::new();
        db.load_font_data(FONT_BYTES.to_vec());
        db.set_sans_serif_family(FONT_FAMILY);
        db.set_serif_family(FONT_FAMILY);
        db.set_monospace_family(FONT_FAMILY);
        db.set_cursive_family(FONT_FAMILY);
        db.set_fantasy_family(FONT_FAMILY);
        Arc::new(db)
    })
    .clone()
}

/// How many colours [`series_color`] has before it repeats.
pub(crate) const PALETTE: usize = 10;

/// The i-th of ten well-separated line colours (matplotlib's "tab10"), cycling.
pub(crate) fn series_color(i: usize) -> RGBColor {
    const TAB10: [(u8, u8, u8); 10] = [
        (31, 119, 180),
        (255, 127, 14),
        (44, 160, 44),
        (214, 39, 40),
        (148, 103, 189),
        (140, 86, 75),
        (227, 119, 194),
        (127, 127, 127),
        (188, 189, 34),
        (23, 190, 207),
    ];
    let (r, g, b) = TAB10[i % TAB10.len()];
    RGBColor(r, g, b)
}

/// A light sequential colour map (white → yellow → orange → dark red) for heatmaps under
/// black contour lines; `t` is clamped to [0, 1].
pub(crate) fn heat_color(t: f64) -> RGBColor {
    const STOPS: [(f64, [f64; 3]); 5] = [
        (0.0, [255.0, 255.0, 255.0]),
        (0.25, [255.0, 237.0, 160.0]),
        (0.5, [254.0, 178.0, 76.0]),
        (0.75, [240.0, 59.0, 32.0]),
        (1.0, [128.0, 0.0, 38.0]),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let k = STOPS
        .windows(2)
        .position(|w| t <= w[1].0)
        .unwrap_or(STOPS.len() - 2);
    let (t0, c0) = STOPS[k];
    let (t1, c1) = STOPS[k + 1];
    let f = (t - t0) / (t1 - t0);
    let mix = |j: usize| (c0[j] + f * (c1[j] - c0[j])).round() as u8;
    RGBColor(mix(0), mix(1), mix(2))
}

pub use crate::error::fmt_num;

/// A tick label on a linear axis: like [`fmt_num`], but rounding noise around zero
/// (|v| < 1e-9) shows as 0.
pub(crate) fn fmt_tick(v: f64) -> String {
    if v.abs() < 1e-9 {
        "0".into()
    } else {
        fmt_num(v)
    }
}

/// `text` in lines of at most `width` characters, broken at white space (a longer word
/// keeps its own line).
pub(crate) fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        if !line.is_empty() && line.chars().count() + 1 + word.chars().count() > width {
            lines.push(std::mem::take(&mut line));
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(word);
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_by_extension() {
        assert_eq!(Format::of(Path::new("a/b.PNG")).unwrap(), Format::Png);
        assert_eq!(Format::of(Path::new("b.svg")).unwrap(), Format::Svg);
        assert!(Format::of(Path::new("b.jpg")).is_err());
        assert!(Format::of(Path::new("b")).is_err());
    }

    #[test]
    fn numbers_are_compact() {
        assert_eq!(fmt_num(5.0), "5");
        assert_eq!(fmt_num(0.125), "0.125");
        assert_eq!(fmt_num(12.3456), "12.35");
        assert_eq!(fmt_num(2.5e-7), "2.5e-7");
        assert_eq!(fmt_num(1e-6), "1e-6");
        assert_eq!(fmt_tick(-2.2e-16), "0");
    }

    #[test]
    fn rendering_reads_no_file_an_svg_names() {
        // A red PNG on disk, named by an image element: nothing is drawn from it.
        let dir = tempfile::tempdir().unwrap();
        let png = dir.path().join("red.png");
        let red: Vec<u8> = [200u8, 0, 0].repeat(16);
        image::save_buffer(&png, &red, 4, 4, image::ColorType::Rgb8).unwrap();
        let svg = format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"4\" height=\"4\">\
             <image href=\"{}\" x=\"0\" y=\"0\" width=\"4\" height=\"4\"/></svg>",
            png.display()
        );
        assert!(svg_to_rgb(&svg, (4, 4)).unwrap().iter().all(|&b| b == 255));
    }

    #[test]
    fn heat_map_ends() {
        assert_eq!(heat_color(0.0), RGBColor(255, 255, 255));
        assert_eq!(heat_color(1.0), RGBColor(128, 0, 38));
        assert_eq!(heat_color(f64::NAN), RGBColor(255, 255, 255));
    }
}
