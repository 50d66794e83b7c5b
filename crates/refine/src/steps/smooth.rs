//! S — smooth_labels (`smooth_radius_m`): after the steps, every body point takes the body
//! label most body points around it carry.

use super::cells::{CellScratch, LabelCells, winner};
use bodyseg_core::math::Vec3;
use bodyseg_core::{Label, NUM_CLASSES};
use rustc_hash::FxHashMap as HashMap;

/// S — smooth_labels (`smooth_radius_m`): every body-labelled point takes the body label
/// most body-labelled points within `radius_m` carry (each weighing
/// `1 / (1 + (d / radius_m)²)`, the point itself included; ties keep its own). All points
/// are judged on the labels as given, so the result does not depend on order. Background
/// and unknown points neither vote nor change: a body point never becomes background here.
///
/// Why: after M, R and N a person's labels still hold islands of another part smaller than
/// a cluster the steps act on (a few centimetres of upper arm on the torso, a patch of
/// lower leg on the thigh), and the parser's part boundaries are ragged; the surface around
/// a point says better which part it lies on. A vote over body labels only, so that the
/// floor or a wall does not outvote a foot or a hand. Measured on the tune sets of
/// docs/notes/2026-11-30-improved-refinement-tuning.md.
///
/// How: as [`reassign_doubted_wide`](super::reassign_doubted_wide), the body points are counted per label in cells of
/// `radius_m / 8`, and the points of one cell share the vote asked from its centre.
pub fn smooth_labels(positions_m: &[Vec3], labels: &[Label], radius_m: f32) -> Vec<Label> {
    smooth_labels_with(positions_m, labels, radius_m, true)
}

/// [`smooth_labels`], asking every point's vote when `skip_single_class` is false (the
/// tests check that skipping changes nothing).
fn smooth_labels_with(
    positions_m: &[Vec3],
    labels: &[Label],
    radius_m: f32,
    skip_single_class: bool,
) -> Vec<Label> {
    let body: Vec<u32> = (0..positions_m.len() as u32)
        .filter(|&i| labels[i as usize].is_body())
        .collect();
    if body.is_empty() || radius_m <= 0.0 {
        return labels.to_vec();
    }
    // Every cell within the radius votes.
    let cells = LabelCells::new(positions_m, labels, &body, radius_m, usize::MAX);
    // Most of a body lies farther than the radius from any other part: there the vote can
    // only name the own label, so it is not asked. The classes of the cells per block of
    // side a little over the radius, placed by their centroids (the voters): every voter
    // within the radius of a cell's centre lies in the 3×3×3 blocks around the centre's
    // block (the margin keeps rounding from breaking that).
    let block_m = radius_m * 1.01;
    let block_of = |p: Vec3| p.map(|x| (x / block_m).floor() as i32);
    let mut classes_in: HashMap<[i32; 3], u16> = HashMap::default();
    for (centroid, counts) in cells.centroids.iter().zip(&cells.counts) {
        let present = (0..NUM_CLASSES)
            .filter(|&c| counts[c] > 0.0)
            .fold(0u16, |m, c| m | 1 << c);
        *classes_in.entry(block_of(*centroid)).or_default() |= present;
    }
    let mut classes_around: HashMap<[i32; 3], u16> = HashMap::default();
    let mut out = labels.to_vec();
    let mut scratch = CellScratch::default();
    let mut cell_votes: HashMap<[i32; 3], Option<[f32; NUM_CLASSES]>> = HashMap::default();
    for &i in &body {
        let i = i as usize;
        let at = cells.key(positions_m[i]);
        let b = block_of(cells.centre(at));
        let around = *classes_around.entry(b).or_insert_with(|| {
            let mut m = 0;
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let n = [b[0] + dx, b[1] + dy, b[2] + dz];
                        m |= classes_in.get(&n).copied().unwrap_or(0);
                    }
                }
            }
            m
        });
        if skip_single_class && around.count_ones() == 1 {
            continue; // Only the point's own class within reach.
        }
        let around = *cell_votes
            .entry(at)
            .or_insert_with(|| cells.votes_around(at, &mut scratch));
        let own = labels[i].class().map(|c| usize::from(c.id()));
        if let Some(b) = around.and_then(|v| winner(&v, own)) {
            out[i] = Label::from_id(b as u8).unwrap_or(labels[i]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::tests::rng_from;

    #[test]
    fn smoothing_gives_islands_to_the_part_around_them_and_never_touches_background() {
        use bodyseg_core::Class;
        let torso = Label::from(Class::Torso);
        let arm = Label::from(Class::UpperArms);
        let leg = Label::from(Class::LowerLegs);
        // A 30 x 30 torso patch, 1 cm apart, holding a 2 x 2 island of upper arm.
        let mut pos = Vec::new();
        let mut labels = Vec::new();
        for i in 0..30 {
            for j in 0..30 {
                pos.push([i as f32 * 0.01, j as f32 * 0.01, 1.0]);
                let island = (14..16).contains(&i) && (14..16).contains(&j);
                labels.push(if island { arm } else { torso });
            }
        }
        // A foot: 6 lower-leg points on a floor of 400 background points, 1 m away from
        // the torso; and an unknown point inside the torso patch.
        for i in 0..20 {
            for j in 0..20 {
                pos.push([3.0 + i as f32 * 0.01, j as f32 * 0.01, 0.0]);
                labels.push(Label::BACKGROUND);
            }
        }
        for k in 0..6 {
            pos.push([3.1 + 0.005 * k as f32, 0.1, 0.005]);
            labels.push(leg);
        }
        pos.push([0.105, 0.105, 1.0]);
        labels.push(Label::UNKNOWN);
        let out = smooth_labels(&pos, &labels, 0.05);
        for (i, (o, l)) in out.iter().zip(&labels).enumerate() {
            if *l == arm {
                assert_eq!(*o, torso, "island point {i} goes to the torso around it");
            } else {
                assert_eq!(o, l, "point {i} ({l:?}) keeps its label");
            }
        }
        // The result does not depend on the order of the points.
        let rev_pos: Vec<Vec3> = pos.iter().rev().copied().collect();
        let rev_labels: Vec<Label> = labels.iter().rev().copied().collect();
        let rev_out: Vec<Label> = smooth_labels(&rev_pos, &rev_labels, 0.05)
            .into_iter()
            .rev()
            .collect();
        assert_eq!(rev_out, out);
        // Off: unchanged.
        assert_eq!(smooth_labels(&pos, &labels, 0.0), labels);
    }

    #[test]
    fn smoothing_skips_only_votes_that_cannot_change_a_label() {
        let mut rng = rng_from(11);
        let mut moved_cases = 0;
        for case in 0..30 {
            // Parts as slabs along x with islands and strays of other parts, some
            // background and unknown, at several densities and radii.
            let n = 2000 + 397 * case;
            let width = 0.05 + 0.01 * (case % 7) as f32;
            let mut pos = Vec::with_capacity(n);
            let mut labels = Vec::with_capacity(n);
            for _ in 0..n {
                let p = [rng() * 0.6, rng() * 0.3, rng() * 0.2];
                let slab = (p[0] / width) as u8 % 6 + 1;
                let r = rng();
                let id = if r < 0.05 {
                    0
                } else if r < 0.08 {
                    1 + (rng() * 6.0) as u8 % 6
                } else {
                    slab
                };
                pos.push(p);
                labels.push(if r > 0.99 {
                    Label::UNKNOWN
                } else {
                    Label::from_id_or_unknown(id)
                });
            }
            let radius = 0.02 + 0.01 * (case % 5) as f32;
            let fast = smooth_labels_with(&pos, &labels, radius, true);
            let slow = smooth_labels_with(&pos, &labels, radius, false);
            assert_eq!(fast, slow, "case {case}");
            moved_cases += usize::from(slow != labels);
        }
        assert!(
            moved_cases >= 20,
            "the vote moved labels in {moved_cases} of 30 cases"
        );
    }

    #[test]
    fn smoothing_keeps_a_straight_boundary_between_two_parts() {
        let torso = Label::from(bodyseg_core::Class::Torso);
        let arm = Label::from(bodyseg_core::Class::UpperArms);
        // Two halves of a plane: a point's own half always holds the larger vote (the
        // boundary column is nearer its own side's points), so nothing moves.
        let mut pos = Vec::new();
        let mut labels = Vec::new();
        for i in 0..40 {
            for j in 0..20 {
                pos.push([i as f32 * 0.01 + 0.0005, j as f32 * 0.01, 1.0]);
                labels.push(if i < 20 { torso } else { arm });
            }
        }
        let out = smooth_labels(&pos, &labels, 0.05);
        let moved = out.iter().zip(&labels).filter(|(a, b)| a != b).count();
        assert!(moved <= 4, "{moved} points crossed a straight boundary");
    }
}
