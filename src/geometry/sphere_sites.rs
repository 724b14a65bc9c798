//! Random non-overlapping centres for free spheres in a box (issue 21,
//! beyond the papers): random sequential addition with a seeded generator,
//! so the same seed gives the same spheres on every machine and rank
//! count. Pure.

use super::point_grid::PointGrid;

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// Tries per sphere before the box is called too full.
pub const TRIES_PER_SPHERE: usize = 1000;

/// Centres of `count` spheres of radius `radius` wholly inside the box
/// [`min`, `max`], at least `gap` apart surface to surface, drawn
/// uniformly one after another (each new centre kept if it clears those
/// kept). Errors name the key that is wrong: `radius` or `gap` not
/// positive (`gap` may be 0), a box thinner than a diameter, or `count`
/// more than fit in [`TRIES_PER_SPHERE`] tries each.
pub fn box_sites(
    count: usize,
    radius: f64,
    gap: f64,
    min: [f64; 3],
    max: [f64; 3],
    seed: u64,
) -> Result<Vec<[f64; 3]>, String> {
    if !(radius.is_finite() && radius > 0.0) {
        return Err(format!("radius: must be positive, got {radius}"));
    }
    if !(gap.is_finite() && gap >= 0.0) {
        return Err(format!("gap: must be non-negative, got {gap}"));
    }
    for d in 0..3 {
        if !(min[d].is_finite() && max[d].is_finite() && max[d] - min[d] >= 2.0 * radius) {
            return Err(format!(
                "box: the box {min:?}..{max:?} must be finite and at least a diameter ({}) wide",
                2.0 * radius
            ));
        }
    }
    let clear = 2.0 * radius + gap;
    let mut grid = PointGrid::new(clear);
    let mut out: Vec<[f64; 3]> = Vec::with_capacity(count);
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut tries = 0usize;
    while out.len() < count {
        if tries >= TRIES_PER_SPHERE * count {
            return Err(format!(
                "count: only {} of {count} spheres of radius {radius} (gap {gap}) fit in the box \
                 {min:?}..{max:?} after {tries} random tries; enlarge the box or lower the count",
                out.len()
            ));
        }
        tries += 1;
        let p: [f64; 3] = std::array::from_fn(|d| rng.gen_range(min[d] + radius..=max[d] - radius));
        let mut free = true;
        grid.near(p, |k| {
            let q = out[k as usize];
            let d2: f64 = (0..3).map(|d| (p[d] - q[d]).powi(2)).sum();
            free = d2 >= clear * clear;
            free
        });
        if free {
            grid.insert(p, out.len() as u32);
            out.push(p);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spheres_lie_in_the_box_apart_and_repeat_with_the_seed() {
        let (r, gap) = (0.01, 0.002);
        let (min, max) = ([0.0, 0.0, 0.0], [0.2, 0.1, 0.1]);
        let s = box_sites(60, r, gap, min, max, 7).unwrap();
        assert_eq!(s.len(), 60);
        for p in &s {
            for d in 0..3 {
                assert!(p[d] >= min[d] + r && p[d] <= max[d] - r, "{p:?}");
            }
        }
        for i in 0..s.len() {
            for j in 0..i {
                let d: f64 = (0..3)
                    .map(|k| (s[i][k] - s[j][k]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                assert!(d >= 2.0 * r + gap, "{i} {j}: {d}");
            }
        }
        assert_eq!(s, box_sites(60, r, gap, min, max, 7).unwrap());
        assert_ne!(s, box_sites(60, r, gap, min, max, 8).unwrap());
    }

    #[test]
    fn bad_or_overfull_boxes_name_the_key() {
        let b = ([0.0; 3], [0.1; 3]);
        let e = box_sites(10, 0.0, 0.0, b.0, b.1, 1).unwrap_err();
        assert!(e.starts_with("radius:"), "{e}");
        let e = box_sites(10, 0.01, -1.0, b.0, b.1, 1).unwrap_err();
        assert!(e.starts_with("gap:"), "{e}");
        let e = box_sites(10, 0.06, 0.0, b.0, b.1, 1).unwrap_err();
        assert!(e.starts_with("box:"), "{e}");
        // 1000 spheres of diameter 0.02 cannot fit in a 0.1 m cube (125 at most).
        let e = box_sites(1000, 0.01, 0.0, b.0, b.1, 1).unwrap_err();
        assert!(e.starts_with("count: only"), "{e}");
    }
}
