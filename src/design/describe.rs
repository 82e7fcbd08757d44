//! The design in one sentence a physicist can act on: what becomes determined, to what
//! precision, with how many samples, where — or that no reachable geometry helps, and which
//! offered wavelength would.

use super::{Design, Scene, DETERMINED_RELATIVE_SE};

/// The target as a reader writes it (σ, T/σ; `all`: every parameter).
pub fn target_label(target: &str) -> String {
    if target.eq_ignore_ascii_case("all") {
        return "every parameter".into();
    }
    target.replace("sigma", "σ").replace("kappa", "κ")
}

/// A relative standard error as a percentage (`±8 %`, `±0.6 %`).
pub fn percent(r: f64) -> String {
    let p = 100.0 * r;
    if p >= 10.0 {
        format!("±{p:.0} %")
    } else if p >= 1.0 {
        format!("±{p:.1} %")
    } else {
        format!("±{p:.2} %")
    }
}

fn range(v: impl Iterator<Item = f64> + Clone) -> (f64, f64) {
    let lo = v.clone().fold(f64::INFINITY, f64::min);
    let hi = v.fold(f64::NEG_INFINITY, f64::max);
    (lo, hi)
}

fn span(name: &str, (lo, hi): (f64, f64)) -> String {
    if lo == hi {
        format!("{name} = {lo}°")
    } else {
        format!("{name} {lo}–{hi}°")
    }
}

/// Where a set of geometries (degrees) lies, in words: `θi = θr from 77.5 to 85° in the
/// plane of incidence (specular side)`, or the ranges of θi, θr and φr.
pub fn where_(angles: &[[f64; 3]]) -> String {
    if angles.is_empty() {
        return "no geometry".into();
    }
    let ti = range(angles.iter().map(|a| a[0]));
    let tr = range(angles.iter().map(|a| a[1]));
    let phi = range(angles.iter().map(|a| a[2].abs()));
    let forward = phi.1 == 0.0;
    let mirror = forward && angles.iter().all(|a| (a[0] - a[1]).abs() < 1e-9);
    if mirror {
        return if ti.0 == ti.1 {
            format!("θi = θr = {}° (the mirror direction)", ti.0)
        } else {
            format!("θi = θr from {}° to {}° (the mirror direction)", ti.0, ti.1)
        };
    }
    let side = if forward {
        " in the plane of incidence, specular side (φr = 0)".to_string()
    } else if phi.0 == 180.0 {
        " in the plane of incidence, back side (φr = 180°)".to_string()
    } else if angles
        .iter()
        .all(|a| a[2].abs() == 0.0 || a[2].abs() == 180.0)
    {
        " in the plane of incidence".to_string()
    } else {
        format!(", {}", span("|φr|", phi))
    };
    format!("{}, {}{side}", span("θi", ti), span("θr", tr))
}

/// The design's sentence (see the module doc).
pub(super) fn sentence(d: &Design, scene: &Scene, n: usize) -> String {
    let label = target_label(&d.target);
    let k = d.chosen.len();
    if k == 0 {
        return format!(
            "no candidate geometry is within the instrument's dynamic range and carries information on {label}: nothing to propose"
        );
    }
    let determined = |r: Option<f64>| r.is_some_and(|r| r <= DETERMINED_RELATIVE_SE);
    let now = match d.target_before {
        Some(r) => format!("now {}", percent(r)),
        None => "now not determined".into(),
    };
    let samples = if k < n {
        format!("{k} samples (all the reachable candidates)")
    } else {
        format!("{k} samples")
    };
    let at = where_(&d.chosen);
    let subject = if d.target.eq_ignore_ascii_case("all") {
        "the least determined parameter".to_string()
    } else {
        label.clone()
    };
    if let Some(a) = d.target_after.filter(|&r| determined(Some(r))) {
        let verb = if determined(d.target_before) {
            "is determined to"
        } else {
            "becomes determined to"
        };
        return format!(
            "{subject} {verb} {} with {samples} at {at} ({now})",
            percent(a)
        );
    }
    let helps = match (d.target_before, d.target_after) {
        (_, None) => false,
        (None, Some(_)) => true,
        (Some(b), Some(a)) => a < 0.9 * b,
    };
    let mut s = format!("no reachable geometry determines {label} at this wavelength");
    s += &match (helps, d.target_after) {
        (true, Some(a)) => format!(
            ": the best {samples}, at {at}, bring it to {} ({now})",
            percent(a)
        ),
        _ => format!(" ({now}; the best {samples} leave it so)"),
    };
    let unit = &scene_unit(scene);
    let best = d
        .alternatives
        .iter()
        .filter(|a| determined(a.target_after))
        .min_by(|a, b| {
            a.target_after
                .partial_cmp(&b.target_after)
                .unwrap_or(std::cmp::Ordering::Equal)
        });
    match best {
        Some(a) => {
            s += &format!(
                "; a measurement at {}{unit} would: {} with {} samples at {}",
                a.wavelength,
                percent(a.target_after.unwrap_or(f64::NAN)),
                a.chosen.len(),
                where_(&a.chosen)
            );
        }
        None if !d.alternatives.is_empty() => {
            s += "; nor would any of the wavelengths offered";
        }
        None => {}
    }
    s
}

fn scene_unit(scene: &Scene) -> String {
    match scene.unit.as_deref() {
        Some(u) if !u.is_empty() => format!(" {u}"),
        _ => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn where_names_the_mirror_direction_and_the_ranges() {
        let m = [[80.0, 80.0, 0.0], [85.0, 85.0, 0.0]];
        assert_eq!(where_(&m), "θi = θr from 80° to 85° (the mirror direction)");
        let back = [[10.0, 20.0, 180.0], [30.0, 40.0, -180.0]];
        assert_eq!(
            where_(&back),
            "θi 10–30°, θr 20–40° in the plane of incidence, back side (φr = 180°)"
        );
        assert_eq!(percent(0.083), "±8.3 %");
        assert_eq!(percent(0.5), "±50 %");
        assert_eq!(target_label("T/sigma"), "T/σ");
    }
}
