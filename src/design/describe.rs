//! The design in one sentence a physicist can act on: what becomes determined, to what
//! precision, with how many samples, where — or that no reachable geometry helps, and which
//! offered wavelength would.

use super::{Design, Scene, DETERMINED_RELATIVE_SE};

/// The target as a reader writes it (σ, T/σ; `all`: every parameter).
pub(crate) fn target_label(target: &str) -> String {
    if target.eq_ignore_ascii_case("all") {
        return "every parameter".into();
    }
    target.replace("sigma", "σ").replace("kappa", "κ")
}

/// A relative standard error as a percentage (`±8 %`, `±0.6 %`).
pub(crate) fn percent(r: f64) -> String {
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

/// Where a group of geometries (degrees) on one side lies: `θi = θr from 77.5° to 85°`,
/// or the ranges of θi and θr (and of |φr| when out of the plane of incidence).
fn group(angles: &[[f64; 3]]) -> String {
    let ti = range(angles.iter().map(|a| a[0]));
    let tr = range(angles.iter().map(|a| a[1]));
    let phi = range(angles.iter().map(|a| a[2].abs()));
    let in_plane = angles
        .iter()
        .all(|a| a[2].abs() == 0.0 || a[2].abs() == 180.0);
    let mirror = phi.1 == 0.0 && angles.iter().all(|a| (a[0] - a[1]).abs() < 1e-9);
    if mirror {
        return if ti.0 == ti.1 {
            format!("θi = θr = {}°", ti.0)
        } else {
            format!("θi = θr from {}° to {}°", ti.0, ti.1)
        };
    }
    let mut s = format!("{}, {}", span("θi", ti), span("θr", tr));
    if !in_plane {
        s += &format!(", {}", span("|φr|", phi));
    }
    s
}

/// Where a set of geometries (degrees) lies, as the rest of a phrase `with 20 samples…`:
/// ` at θi 77.5–85°, θr 77.5–85° on the specular side, in the plane of incidence`, or for
/// both sides `: 11 at … on the specular side and 9 at … on the back side`.
pub(crate) fn where_(angles: &[[f64; 3]]) -> String {
    if angles.is_empty() {
        return " (none)".into();
    }
    let (front, back): (Vec<[f64; 3]>, Vec<[f64; 3]>) =
        angles.iter().partition(|a| a[2].abs() <= 90.0);
    let plane = if angles
        .iter()
        .all(|a| a[2].abs() == 0.0 || a[2].abs() == 180.0)
    {
        ", in the plane of incidence"
    } else {
        ""
    };
    match (front.is_empty(), back.is_empty()) {
        (false, true) => format!(" at {} on the specular side{plane}", group(&front)),
        (true, false) => format!(" at {} on the back side{plane}", group(&back)),
        _ => format!(
            ": {} at {} on the specular side and {} at {} on the back side{plane}",
            front.len(),
            group(&front),
            back.len(),
            group(&back)
        ),
    }
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
        Some(r) if r <= DETERMINED_RELATIVE_SE => format!("now {}", percent(r)),
        Some(r) => format!("now not determined: {} linearised", percent(r)),
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
        return format!("{subject} {verb} {} with {samples}{at} ({now})", percent(a));
    }
    let helps = match (d.target_before, d.target_after) {
        (_, None) => false,
        (None, Some(_)) => true,
        (Some(b), Some(a)) => a < 0.9 * b,
    };
    let mut s = format!("no reachable geometry determines {label} at this wavelength");
    s += &match (helps, d.target_after) {
        (true, Some(a)) => format!(" ({now}; {} with the best {samples}{at})", percent(a)),
        _ => format!(" ({now}; the best {samples} leave it so)"),
    };
    let unit = &scene_unit(scene);
    let best = d
        .alternatives
        .iter()
        .filter_map(|a| Some((a, a.target_after.filter(|&r| determined(Some(r)))?)))
        .min_by(|a, b| a.1.total_cmp(&b.1));
    match best {
        Some((a, r)) => {
            s += &format!(
                "; a measurement at {}{unit} would: {} with {} samples{}",
                a.wavelength,
                percent(r),
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
        assert_eq!(
            where_(&m),
            " at θi = θr from 80° to 85° on the specular side, in the plane of incidence"
        );
        let both = [
            [10.0, 20.0, 180.0],
            [30.0, 40.0, -180.0],
            [80.0, 70.0, 45.0],
        ];
        assert_eq!(
            where_(&both),
            ": 1 at θi = 80°, θr = 70°, |φr| = 45° on the specular side and 2 at θi 10–30°, θr 20–40° on the back side"
        );
        assert_eq!(percent(0.083), "±8.3 %");
        assert_eq!(percent(0.5), "±50 %");
        assert_eq!(target_label("T/sigma"), "T/σ");
    }
}
