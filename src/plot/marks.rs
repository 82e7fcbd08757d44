//! Marks shared by the charts: values beyond an axis' end drawn as arrows at the edge
//! (counted in the legend, never clamped silently), and point labels placed so that they
//! overlap neither each other nor the points.

use super::fmt_num;

/// The values beyond a limit: how many, and the farthest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Beyond {
    /// How many finite values lie beyond the limit (NaN and infinities are not counted).
    pub count: usize,
    /// The farthest of them from the edge (the largest above a top, the smallest below a
    /// bottom), in the values' own unit; 0 when `count` is 0.
    pub worst: f64,
    /// Whether the values lie below a bottom (else above a top).
    pub below: bool,
}

impl Beyond {
    /// The finite values above `limit`.
    pub(crate) fn above(values: impl IntoIterator<Item = f64>, limit: f64) -> Beyond {
        let beyond = values.into_iter().filter(|v| v.is_finite() && *v > limit);
        Beyond::gather(beyond, false)
    }

    /// The finite values below `limit`.
    pub(crate) fn below(values: impl IntoIterator<Item = f64>, limit: f64) -> Beyond {
        let beyond = values.into_iter().filter(|v| v.is_finite() && *v < limit);
        Beyond::gather(beyond, true)
    }

    /// The count and the farthest of `beyond` (the smallest when `below`).
    fn gather(beyond: impl Iterator<Item = f64>, below: bool) -> Beyond {
        let farther = |a: f64, b: f64| if below { a.min(b) } else { a.max(b) };
        let mut out = Beyond {
            count: 0,
            worst: 0.0,
            below,
        };
        for v in beyond {
            out.worst = if out.count == 0 {
                v
            } else {
                farther(out.worst, v)
            };
            out.count += 1;
        }
        out
    }

    /// The legend text: "3 measured beyond the rim (up to 55.14× L_max)" ("down to" below
    /// a bottom); `what` names the edge ("beyond the rim"), `unit` follows the farthest
    /// value ("× L_max" or "").
    pub(crate) fn label(&self, what: &str, unit: &str) -> String {
        let bound = if self.below { "down to" } else { "up to" };
        format!(
            "{} measured {what} ({bound} {}{unit})",
            self.count,
            fmt_num(self.worst)
        )
    }
}

/// An arrow ending at the origin (its tip), pointing along `dir` (pixels; y down): the
/// shaft of `len` pixels and a head of `head` pixels, as one polyline of pixel offsets from
/// the tip (tail → tip → one barb → tip → the other barb).
pub(crate) fn arrow(dir: (f64, f64), len: f64, head: f64) -> Vec<(i32, i32)> {
    let n = (dir.0 * dir.0 + dir.1 * dir.1).sqrt();
    let (ux, uy) = if n > 0.0 {
        (dir.0 / n, dir.1 / n)
    } else {
        (0.0, -1.0)
    };
    let p = |x: f64, y: f64| (x.round() as i32, y.round() as i32);
    // Barbs at ±30° from the shaft.
    let (c, s) = (0.866 * head, 0.5 * head);
    vec![
        p(-len * ux, -len * uy),
        (0, 0),
        p(-c * ux + s * uy, -c * uy - s * ux),
        (0, 0),
        p(-c * ux - s * uy, -c * uy + s * ux),
    ]
}

/// The legend glyph of an arrow: pointing right, its tip `len` pixels right of (x, y).
pub(crate) fn arrow_glyph((x, y): (i32, i32), len: i32) -> Vec<(i32, i32)> {
    arrow((1.0, 0.0), len as f64, 7.0)
        .into_iter()
        .map(|(dx, dy)| (x + len + dx, y + dy))
        .collect()
}

/// A pixel rectangle: left, top, width, height.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Rect {
    /// The left edge, pixels from the drawing area's left (grows rightwards).
    pub x: f64,
    /// The top edge, pixels from the drawing area's top (grows downwards).
    pub y: f64,
    /// The width in pixels: the box spans `x` to `x + w`.
    pub w: f64,
    /// The height in pixels: the box spans `y` down to `y + h`.
    pub h: f64,
}

impl Rect {
    /// Whether the two rectangles share interior points.
    pub(crate) fn overlaps(&self, o: &Rect) -> bool {
        self.x < o.x + o.w && o.x < self.x + self.w && self.y < o.y + o.h && o.y < self.y + self.h
    }

    /// Whether `self` lies inside `o`.
    pub(crate) fn inside(&self, o: &Rect) -> bool {
        self.x >= o.x
            && self.y >= o.y
            && self.x + self.w <= o.x + o.w
            && self.y + self.h <= o.y + o.h
    }
}

/// Where a point's label goes: the top-left corner of its text box, in pixel offsets from
/// the point, and whether a leader line joins them (a label moved away from its point).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Placed {
    /// Pixels from the point to the text box's left edge (negative: the box starts left of
    /// the point).
    pub dx: f64,
    /// Pixels from the point down to the text box's top edge (negative: above the point).
    pub dy: f64,
    /// The label sits beyond the first ring of positions, so a line is drawn from the point
    /// to the nearest point of the label's box.
    pub leader: bool,
}

/// Place labels of sizes `sizes` (pixels) beside points `points` (pixels) inside `area`:
/// each label takes the first candidate position (right, left, above, below and the four
/// diagonals, then the same directions 2, 3, 4 and 5 times farther, with a leader line)
/// whose box overlaps no earlier label, no point's marker (`radius` pixels) and stays in
/// `area`. A label with no such position takes the one overlapping the fewest boxes.
pub(crate) fn place_labels(
    points: &[(f64, f64)],
    sizes: &[(f64, f64)],
    radius: f64,
    area: Rect,
) -> Vec<Placed> {
    let markers: Vec<Rect> = points
        .iter()
        .map(|&(x, y)| Rect {
            x: x - radius,
            y: y - radius,
            w: 2.0 * radius,
            h: 2.0 * radius,
        })
        .collect();
    let mut taken: Vec<Rect> = Vec::new();
    let mut out = Vec::with_capacity(points.len());
    for (&(px, py), &(w, h)) in points.iter().zip(sizes) {
        let gap = radius + 3.0;
        let mut best: Option<(usize, Placed, Rect)> = None;
        'search: for ring in 1..=5 {
            let d = gap + (ring - 1) as f64 * (h + 4.0);
            let candidates = [
                (d, -0.5 * h),
                (-d - w, -0.5 * h),
                (-0.5 * w, -d - h),
                (-0.5 * w, d),
                (d, -d - 0.6 * h),
                (d, d - 0.4 * h),
                (-d - w, -d - 0.6 * h),
                (-d - w, d - 0.4 * h),
            ];
            for (dx, dy) in candidates {
                let r = Rect {
                    x: px + dx,
                    y: py + dy,
                    w,
                    h,
                };
                let hits = taken
                    .iter()
                    .chain(&markers)
                    .filter(|o| o.overlaps(&r))
                    .count()
                    + usize::from(!r.inside(&area));
                let placed = Placed {
                    dx,
                    dy,
                    leader: ring > 1,
                };
                if best.as_ref().is_none_or(|b| hits < b.0) {
                    best = Some((hits, placed, r));
                }
                if hits == 0 {
                    break 'search;
                }
            }
        }
        let (_, placed, r) = best.expect("at least one candidate");
        taken.push(r);
        out.push(placed);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_what_is_beyond() {
        let b = Beyond::above([0.5, 2.0, f64::NAN, 55.0, 1.0], 1.15);
        assert_eq!(
            b,
            Beyond {
                count: 2,
                worst: 55.0,
                below: false,
            }
        );
        assert_eq!(
            b.label("beyond the rim", "× L_max"),
            "2 measured beyond the rim (up to 55× L_max)"
        );
    }

    #[test]
    fn arrows_point_where_asked() {
        // Up (y down on screen): the tail is below the tip, the barbs below it too.
        let a = arrow((0.0, -1.0), 12.0, 6.0);
        assert_eq!(a[0], (0, 12));
        assert_eq!(a[1], (0, 0));
        assert!(a[2].1 > 0 && a[4].1 > 0 && a[2].0 == -a[4].0);
    }

    #[test]
    fn labels_of_a_cluster_do_not_overlap() {
        // Ten points within a few pixels of each other, as the work-precision plot's
        // fits with equal error.
        let points: Vec<(f64, f64)> = (0..10).map(|k| (300.0 + 3.0 * k as f64, 200.0)).collect();
        let sizes = vec![(120.0, 14.0); 10];
        let area = Rect {
            x: 0.0,
            y: 0.0,
            w: 800.0,
            h: 500.0,
        };
        let placed = place_labels(&points, &sizes, 5.0, area);
        let boxes: Vec<Rect> = placed
            .iter()
            .zip(&points)
            .map(|(p, q)| Rect {
                x: q.0 + p.dx,
                y: q.1 + p.dy,
                w: 120.0,
                h: 14.0,
            })
            .collect();
        for (i, a) in boxes.iter().enumerate() {
            assert!(a.inside(&area));
            for b in &boxes[i + 1..] {
                assert!(!a.overlaps(b), "{a:?} {b:?}");
            }
        }
        assert!(!placed[0].leader, "the first label sits beside its point");
    }
}
