//! A lit sphere rendered with any model (Peters 2000, Figure 4; geometry eq. 2–8).
//!
//! The sphere inscribes a square frame and is viewed along +z (x right, y up). The light
//! is at `light_deg` from z in the xz-plane on the −x side, ŝ = (−sin θ, 0, cos θ). Each
//! pixel's normal n̂ = (x, y, √(1 − x² − y²)) gives the local angles through
//! [`Sample::from_vectors`]`(ŝ, n̂, +z)`; pixels with θi ≥ 90° are unlit (black), pixels
//! outside the disc are background. Brightness is L normalised to its maximum.
//!
//! Marks (the paper's): '+' at the view direction, '×' at the light direction, '○' at the
//! specular direction (the normal halfway between ŝ and the view).

use super::{font, DrawError, Picture};
use crate::error::{Error, Result};
use crate::geometry::{Geometry, Quantity, Sample};
use crate::model::Model;
use nalgebra::Vector3;
use plotters::coord::Shift;
use plotters::prelude::*;

/// The model's radiance over the sphere's disc, one value per pixel.
#[derive(Debug, Clone)]
pub(crate) struct SphereImage {
    /// Width = height in pixels.
    pub size: u32,
    /// Light direction, degrees from the view direction (+z).
    pub light_deg: f64,
    /// Row-major, top row first: L for lit pixels, 0 for unlit ones, NaN outside the disc.
    pub radiance: Vec<f64>,
}

/// Where the marks go, in sphere coordinates (x, y) ∈ unit disc: view, light, specular.
pub(crate) fn mark_positions(light_deg: f64) -> [(f64, f64); 3] {
    let t = light_deg.to_radians();
    [(0.0, 0.0), (-t.sin(), 0.0), (-(0.5 * t).sin(), 0.0)]
}

/// Evaluate `model` with `params` over a sphere of `size`×`size` pixels.
pub(crate) fn sphere_radiance(
    model: &dyn Model,
    params: &[f64],
    light_deg: f64,
    wavelength: f64,
    size: u32,
) -> Result<SphereImage> {
    crate::model::check_param_count(model, params)?;
    if !(light_deg.is_finite() && (0.0..=90.0).contains(&light_deg)) {
        return Err(Error::Usage(format!(
            "light angle {light_deg}° must lie in [0°, 90°]"
        )));
    }
    if !(8..=8192).contains(&size) {
        return Err(Error::Usage(format!(
            "sphere size {size} px must lie in [8, 8192]"
        )));
    }
    let t = light_deg.to_radians();
    let source = Vector3::new(-t.sin(), 0.0, t.cos());
    let view = Vector3::z();
    let n = size as usize;
    let mut radiance = vec![f64::NAN; n * n];
    let mut samples = Vec::new();
    let mut index = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (x, y) = pixel_xy(size, i, j);
            let r2 = x * x + y * y;
            if r2 > 1.0 {
                continue;
            }
            let k = j * n + i;
            radiance[k] = 0.0;
            let normal = Vector3::new(x, y, (1.0 - r2).sqrt());
            if source.dot(&normal) <= 1e-9 {
                continue;
            }
            let s = Sample::from_vectors(&source, &normal, &view);
            if s.validate().is_err() {
                continue;
            }
            samples.push(s);
            index.push(k);
        }
    }
    if !samples.is_empty() {
        let geo = Geometry::new(&samples, &[wavelength], Quantity::Radiance)?;
        let out = crate::model::domain::evaluate_checked(model, params, &geo)?;
        for (&k, v) in index.iter().zip(out) {
            radiance[k] = v.max(0.0);
        }
    }
    if !radiance.iter().any(|&v| v > 0.0) {
        return Err(Error::Usage(format!(
            "model {} gives no light anywhere on the sphere for {} (every value is zero or negative, or underflows): the picture would be all black",
            model.name(),
            crate::model::domain::describe_params(model, params)
        )));
    }
    Ok(SphereImage {
        size,
        light_deg,
        radiance,
    })
}

/// Sphere coordinates (x right, y up, unit radius) of pixel (column i, row j).
pub(crate) fn pixel_xy(size: u32, i: usize, j: usize) -> (f64, f64) {
    let s = size as f64;
    (
        (i as f64 + 0.5) / s * 2.0 - 1.0,
        1.0 - (j as f64 + 0.5) / s * 2.0,
    )
}

impl SphereImage {
    /// The largest radiance on the disc.
    pub(crate) fn max(&self) -> f64 {
        self.radiance
            .iter()
            .filter(|v| v.is_finite())
            .fold(0.0, |m, &v| m.max(v))
    }

    /// Sphere coordinates (x, y) of the brightest pixel.
    #[cfg(test)]
    pub(crate) fn brightest_xy(&self) -> (f64, f64) {
        let n = self.size as usize;
        let k = self
            .radiance
            .iter()
            .enumerate()
            .filter(|(_, v)| v.is_finite())
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(k, _)| k)
            .unwrap_or(0);
        pixel_xy(self.size, k % n, k / n)
    }

    /// RGB pixels (3 bytes each, row-major): grey level L / L_max, inverted when `negative`;
    /// background black (white in a negative).
    pub(crate) fn to_rgb(&self, negative: bool) -> Vec<u8> {
        let max = self.max();
        let scale = if max > 0.0 { 1.0 / max } else { 0.0 };
        let mut out = Vec::with_capacity(self.radiance.len() * 3);
        for &v in &self.radiance {
            let t = if v.is_finite() {
                (v * scale).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let t = if negative { 1.0 - t } else { t };
            let g = (255.0 * t).round() as u8;
            out.extend_from_slice(&[g, g, g]);
        }
        out
    }
}

/// Draw a sphere image with its top-left corner at pixel `origin` of `area`; with `marks`,
/// the view, light and specular marks and the disc's outline.
pub(crate) fn draw_sphere<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    origin: (i32, i32),
    image: &SphereImage,
    negative: bool,
    marks: bool,
) -> std::result::Result<(), DrawError<DB>> {
    let size = image.size;
    let img = BitMapElement::with_owned_buffer(origin, (size, size), image.to_rgb(negative))
        .expect("buffer has size² pixels");
    area.draw(&img)?;
    if marks {
        let half = size as f64 / 2.0;
        let to_px = |(x, y): (f64, f64)| {
            (
                origin.0 + (half + x * half).round() as i32,
                origin.1 + (half - y * half).round() as i32,
            )
        };
        let color = RGBColor(220, 0, 0);
        let width = (size / 160).max(1);
        let style = color.stroke_width(width);
        let r = (size as i32 / 22).max(3);
        let [view, light, spec] = mark_positions(image.light_deg).map(to_px);
        let outline = if negative {
            RGBColor(120, 120, 120)
        } else {
            RGBColor(90, 90, 90)
        };
        area.draw(&Circle::new(
            to_px((0.0, 0.0)),
            (half.round() as i32 - 1).max(1),
            outline.stroke_width(1),
        ))?;
        area.draw(&PathElement::new(
            vec![(view.0 - r, view.1), (view.0 + r, view.1)],
            style,
        ))?;
        area.draw(&PathElement::new(
            vec![(view.0, view.1 - r), (view.0, view.1 + r)],
            style,
        ))?;
        let d = (r as f64 * 0.75).round() as i32;
        area.draw(&PathElement::new(
            vec![(light.0 - d, light.1 - d), (light.0 + d, light.1 + d)],
            style,
        ))?;
        area.draw(&PathElement::new(
            vec![(light.0 - d, light.1 + d), (light.0 + d, light.1 - d)],
            style,
        ))?;
        area.draw(&Circle::new(spec, d, style))?;
    }
    Ok(())
}

/// One rendered sphere as a picture of exactly `size`×`size` pixels.
#[derive(Debug, Clone)]
pub(crate) struct SpherePicture {
    /// The rendered radiance; its `size` is the picture's width and height in pixels.
    pub image: SphereImage,
    /// Draw as a negative (darker = more light, on white) as in the paper's Figure 4;
    /// false: brighter = more light, on black.
    pub negative: bool,
    /// Draw the disc's outline and the red view (+), light (×) and specular (○) marks.
    pub marks: bool,
}

impl Picture for SpherePicture {
    fn size(&self) -> (u32, u32) {
        (self.image.size, self.image.size)
    }

    fn draw<DB: super::stroke::Canvas>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawError<DB>> {
        root.fill(if self.negative { &WHITE } else { &BLACK })?;
        draw_sphere(root, (0, 0), &self.image, self.negative, self.marks)
    }
}

/// Caption text under a sphere, in the figure font.
pub(crate) fn draw_caption<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    centre: (i32, i32),
    text: &str,
    size: f64,
) -> std::result::Result<(), DrawError<DB>> {
    let style = font(size)
        .color(&BLACK)
        .pos(plotters::style::text_anchor::Pos::new(
            plotters::style::text_anchor::HPos::Center,
            plotters::style::text_anchor::VPos::Top,
        ));
    area.draw_text(text, &style, centre)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{by_name, ModelOptions};

    fn kbs_rough() -> Box<dyn Model> {
        by_name("kbs-rough", &ModelOptions::default()).unwrap()
    }

    #[test]
    fn kbs_highlight_is_at_the_specular_normal() {
        let img = sphere_radiance(kbs_rough().as_ref(), &[1.0, 5.0, 1.0], 45.0, 1.0, 128).unwrap();
        let (x, y) = img.brightest_xy();
        let px = 2.0 / 128.0;
        assert!(
            (x + (22.5f64).to_radians().sin()).abs() <= 1.5 * px,
            "x = {x}"
        );
        assert!(y.abs() <= 1.5 * px, "y = {y}");
    }

    #[test]
    fn lambert_highlight_is_at_the_light() {
        let m = by_name("lambert", &ModelOptions::default()).unwrap();
        let img = sphere_radiance(m.as_ref(), &[1.0], 45.0, 1.0, 128).unwrap();
        let (x, y) = img.brightest_xy();
        let px = 2.0 / 128.0;
        assert!(
            (x + (45f64).to_radians().sin()).abs() <= 1.5 * px,
            "x = {x}"
        );
        assert!(y.abs() <= 1.5 * px, "y = {y}");
    }

    #[test]
    fn unlit_and_outside_pixels() {
        let m = by_name("lambert", &ModelOptions::default()).unwrap();
        let img = sphere_radiance(m.as_ref(), &[1.0], 45.0, 1.0, 64).unwrap();
        // Corner: outside the disc. Far +x edge on the equator: unlit (θi > 90°).
        assert!(img.radiance[0].is_nan());
        assert_eq!(img.radiance[32 * 64 + 63], 0.0);
        let rgb = img.to_rgb(true);
        assert_eq!(&rgb[0..3], &[255, 255, 255]);
        assert!(sphere_radiance(m.as_ref(), &[1.0], 95.0, 1.0, 64).is_err());
        assert!(sphere_radiance(m.as_ref(), &[1.0, 2.0], 45.0, 1.0, 64).is_err());
    }

    #[test]
    fn specular_mark_is_halfway() {
        let [_, light, spec] = mark_positions(45.0);
        assert!((light.0 + std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12);
        assert!((spec.0 + 0.3827).abs() < 1e-4);
    }
}
