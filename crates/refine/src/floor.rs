//! Floor contact (`floor_contact_m`): after the steps, lower-leg points on the floor are the
//! floor.
//!
//! Why: a foot's visible surface is above the floor (its sole faces down), while the 2D
//! parser's leg label bleeds onto the floor around the foot; those points lie in the leg's
//! cluster, so M, R and N keep them.

use crate::steps::quantile;
use bodyseg_core::math::Vec3;
use bodyseg_core::{Class, Label};

/// Lower-leg points lying on the floor become background: a foot's visible surface is
/// above the floor (its sole faces down), so a lower-leg point within `floor_tol_m` of the
/// floor is the floor around the foot, which the 2D parser's leg label bleeds onto. The
/// floor height is the median height of the person's background points lying no higher
/// than [`FLOOR_BAND_M`] above its lowest body points (the [`LOW_BODY_QUANTILE`] of the body
/// points' heights, so that a stray point below the floor does not set it); without
/// [`MIN_FLOOR_POINTS`] of them nothing changes. World z is up (ALGORITHM.md §0).
pub fn floor_contact(positions_m: &[Vec3], labels: &[Label], floor_tol_m: f32) -> Vec<Label> {
    let mut out = labels.to_vec();
    let mut body_z: Vec<f32> = positions_m
        .iter()
        .zip(labels)
        .filter(|(_, l)| l.is_body())
        .map(|(p, _)| p[2])
        .collect();
    if body_z.is_empty() {
        return out;
    }
    let lowest_body = quantile(&mut body_z, LOW_BODY_QUANTILE);
    let mut floor: Vec<f32> = positions_m
        .iter()
        .zip(labels)
        .filter(|(p, l)| **l == Label::BACKGROUND && p[2] <= lowest_body + FLOOR_BAND_M)
        .map(|(p, _)| p[2])
        .collect();
    if floor.len() < MIN_FLOOR_POINTS {
        return out;
    }
    let floor_z = quantile(&mut floor, 0.5);
    let lower_legs = Label::from(Class::LowerLegs);
    for (l, p) in out.iter_mut().zip(positions_m) {
        if *l == lower_legs && p[2] <= floor_z + floor_tol_m {
            *l = Label::BACKGROUND;
        }
    }
    out
}

/// Floor contact: the quantile of the body points' heights taken as the person's lowest.
pub const LOW_BODY_QUANTILE: f64 = 0.005;
/// Floor contact: background points at most this far above the person's lowest body points
/// are taken as the floor, metres.
pub const FLOOR_BAND_M: f32 = 0.05;
/// Floor contact: fewest floor points for a floor height.
pub const MIN_FLOOR_POINTS: usize = 50;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_floor_height_comes_from_the_persons_background_points() {
        // A floor at z = 0.1 m (not 0: it is measured), a stray body point far below it,
        // and two lower-leg points: 3 mm and 3 cm above the floor.
        let mut pos: Vec<Vec3> = (0..100).map(|i| [i as f32 * 0.01, 0.0, 0.1]).collect();
        let mut lab = vec![Label::BACKGROUND; pos.len()];
        let leg = Label::from(Class::LowerLegs);
        pos.extend([[0.0, 0.1, -0.5], [0.0, 0.2, 0.103], [0.0, 0.3, 0.13]]);
        lab.extend([leg; 3]);
        // More body points, so that the stray one is below the low quantile.
        pos.extend((0..400).map(|i| [0.5, 0.5, 0.2 + i as f32 * 0.002]));
        lab.extend(vec![leg; 400]);
        let out = floor_contact(&pos, &lab, 0.006);
        assert_eq!(out[101], Label::BACKGROUND, "3 mm above the floor");
        assert_eq!(out[102], leg, "3 cm above the floor");
        assert!(out[103..].iter().all(|&l| l == leg));
    }
}
