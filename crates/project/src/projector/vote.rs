//! The multi-view consistency vote: a point seen by several cameras takes the label most
//! of them agree on (the paper's "future work"; ALGORITHM.md §3, multi-view).
//!
//! Run after [`FrameProjector::project_frame`] on its cloud, and only when asked for (the
//! refinement's `vote = "multi_view"`): the projection itself does no extra work. The
//! projected labels are left as they are; the vote is a second label list beside them.
//!
//! For point `i` of camera `c` (world position `p`), every other camera `c'` is asked:
//! 1. `p` is moved into `c'`'s depth frame (`world_from_depth` inverted) and projected
//!    with `c'`'s depth intrinsics (distortion included, f32 as [`ColorProjection`]) to
//!    its nearest depth pixel `q`, snapped to the back-projection's stride grid; behind
//!    the sensor or outside the image → no vote;
//! 2. *visibility*: `c'` measured a depth `z_q` at `q` and `p`'s depth along `c'`'s z lies
//!    within `occlusion_tol_m + occlusion_tol_ratio · z_q` of it (the DSA occlusion
//!    test's slack): `c'` sees the same surface there. A point hidden from `c'` (farther),
//!    or one `c'` sees through (nearer: a flying pixel), gets no vote from `c'`;
//! 3. the vote of `c'` is the projected label of `c'`'s own point at `q` — so every
//!    check of the projection (DSA's occlusion, depth edges, boundary vote) applies to
//!    it — unless that label is `unknown`.
//!
//! The point's own projected label votes too (unless unknown). The label with the most
//! votes wins; on a tie the point keeps its own label (an `unknown` point stays unknown
//! when the other views disagree evenly). A point no other camera sees keeps its label.

use bodyseg_calib::BackProjectOptions;
use bodyseg_core::{Label, LabeledCloud, NUM_CLASSES};
use rayon::prelude::*;

use crate::color::ColorProjection;
use crate::dsa::POINTS_PER_CHUNK;
use crate::{CameraImages, FrameProjector, ProjectConfig, ProjectError};

/// No point at this depth pixel.
const NONE: u32 = u32::MAX;

/// One camera as a voter: where a world point lands in its depth image, and its points.
struct Voter<'a> {
    depth_from_world: ColorProjection,
    /// Depth image width and height, pixels.
    w: u32,
    h: u32,
    depth_raw: &'a [u16],
    lut: &'a crate::dsa::DepthLut,
    /// Per depth pixel: the index of this camera's point there in the cloud, or [`NONE`].
    point_at: Vec<u32>,
}

impl FrameProjector {
    /// The multi-view vote (module docs) on `cloud`, a cloud this projector made from
    /// `images` with `opts` (its stride) and `cfg` (its occlusion slack is the
    /// visibility test's): one label per point, in the cloud's order, into `out`
    /// (overwritten). `cloud.labels` is not changed.
    ///
    /// # Errors
    /// `images` does not hold one camera per rig camera or an image has the wrong size;
    /// a point's origin names no camera of the rig or lies outside its depth image; the
    /// configuration is invalid.
    pub fn vote_labels(
        &self,
        images: &[CameraImages<'_>],
        opts: &BackProjectOptions,
        cfg: &ProjectConfig,
        cloud: &LabeledCloud,
        out: &mut Vec<Label>,
    ) -> Result<(), ProjectError> {
        // The projection's own checks: the same errors as the projection that made `cloud`.
        self.check_inputs(images, opts, cfg)?;
        let n = cloud.len();
        for (what, got) in [
            ("labels", cloud.labels.len()),
            ("origins", cloud.origins.len()),
        ] {
            if got != n {
                return Err(ProjectError::SizeMismatch {
                    camera: "(cloud)".into(),
                    what,
                    got,
                    want: n,
                });
            }
        }
        let mut voters: Vec<Voter<'_>> = self
            .cameras
            .iter()
            .zip(images)
            .map(|(t, img)| Voter {
                depth_from_world: ColorProjection::from_pose(
                    &t.camera.world_from_depth.inverse(),
                    &t.camera.depth,
                ),
                w: t.camera.depth.width,
                h: t.camera.depth.height,
                depth_raw: img.depth_raw,
                lut: &t.depth_lut,
                point_at: vec![NONE; t.camera.depth.num_pixels()],
            })
            .collect();
        for (i, o) in cloud.origins.iter().enumerate() {
            let Some(voter) = voters.get_mut(usize::from(o.camera)) else {
                return Err(ProjectError::CameraCount {
                    got: usize::from(o.camera) + 1,
                    want: self.cameras.len(),
                });
            };
            let Some(slot) = voter.point_at.get_mut(o.pixel as usize) else {
                return Err(ProjectError::OriginOutside {
                    camera: self.cameras[usize::from(o.camera)].camera.name.clone(),
                    index: i,
                    pixel: o.pixel,
                });
            };
            *slot = i as u32;
        }

        let stride = opts.stride;
        let (tol_m, tol_ratio) = (cfg.occlusion_tol_m, cfg.occlusion_tol_ratio);
        out.clear();
        out.resize(n, Label::UNKNOWN);
        out.par_chunks_mut(POINTS_PER_CHUNK)
            .enumerate()
            .for_each(|(k, out)| {
                let start = k * POINTS_PER_CHUNK;
                for (j, o) in out.iter_mut().enumerate() {
                    let i = start + j;
                    let own = cloud.labels[i];
                    let mut votes = [0u16; NUM_CLASSES];
                    if let Some(c) = own.class() {
                        votes[c.index()] += 1;
                    }
                    let p = cloud.positions_m[i];
                    let camera = usize::from(cloud.origins[i].camera);
                    for (c, voter) in voters.iter().enumerate() {
                        if c == camera {
                            continue;
                        }
                        let Some(index) = voter.seen_point(p, stride, tol_m, tol_ratio) else {
                            continue;
                        };
                        if let Some(class) = cloud.labels[index].class() {
                            votes[class.index()] += 1;
                        }
                    }
                    *o = majority(own, &votes);
                }
            });
        Ok(())
    }
}

impl Voter<'_> {
    /// The index of this camera's point on the same surface as world point `p` (steps 1
    /// and 2 of the module docs), if any.
    #[inline]
    fn seen_point(&self, p: [f32; 3], stride: u32, tol_m: f64, tol_ratio: f64) -> Option<usize> {
        let (u, v, z_m) = self.depth_from_world.nearest_pixel(p)?;
        let (u, v) = (snap(u, stride, self.w), snap(v, stride, self.h));
        let q = v as usize * self.w as usize + u as usize;
        let index = self.point_at[q];
        if index == NONE {
            return None;
        }
        let z_q = self.lut[usize::from(self.depth_raw[q])];
        // NaN (no measurement) fails the test.
        ((f64::from(z_m) - z_q).abs() <= tol_m + tol_ratio * z_q).then_some(index as usize)
    }
}

/// The stride-grid coordinate (a multiple of `stride` below `size`) nearest to `x`.
#[inline]
fn snap(x: u32, stride: u32, size: u32) -> u32 {
    let s = stride.max(1);
    let k = (x + s / 2) / s * s;
    if k < size { k } else { k - s }
}

/// The label with the most votes; `own` when it is among the most voted, or when several
/// other labels share the most votes (or nobody voted).
fn majority(own: Label, votes: &[u16; NUM_CLASSES]) -> Label {
    let best = votes.iter().copied().max().unwrap_or(0);
    if best == 0 {
        return own;
    }
    if own.class().is_some_and(|c| votes[c.index()] == best) {
        return own;
    }
    let mut winners = votes.iter().enumerate().filter(|&(_, &v)| v == best);
    match (winners.next(), winners.next()) {
        (Some((id, _)), None) => Label::from_id(id as u8).unwrap_or(own),
        _ => own,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bodyseg_core::Class;

    fn votes(pairs: &[(Class, u16)]) -> [u16; NUM_CLASSES] {
        let mut v = [0; NUM_CLASSES];
        for &(c, n) in pairs {
            v[c.index()] += n;
        }
        v
    }

    #[test]
    fn majority_keeps_own_on_ties_and_takes_a_clear_winner() {
        let (head, torso, arm) = (
            Label::from(Class::Head),
            Label::from(Class::Torso),
            Label::from(Class::UpperArms),
        );
        // Own + one other that disagrees: a tie, own kept.
        assert_eq!(
            majority(head, &votes(&[(Class::Head, 1), (Class::Torso, 1)])),
            head
        );
        // Two others against own: theirs.
        assert_eq!(
            majority(head, &votes(&[(Class::Head, 1), (Class::Torso, 2)])),
            torso
        );
        // Unknown own, one view: that view's.
        assert_eq!(
            majority(Label::UNKNOWN, &votes(&[(Class::UpperArms, 1)])),
            arm
        );
        // Unknown own, two views that disagree: unknown stays.
        assert_eq!(
            majority(
                Label::UNKNOWN,
                &votes(&[(Class::UpperArms, 1), (Class::Torso, 1)])
            ),
            Label::UNKNOWN
        );
        // Nobody votes.
        assert_eq!(majority(Label::UNKNOWN, &votes(&[])), Label::UNKNOWN);
        // Three different labels, one each: own.
        assert_eq!(
            majority(
                head,
                &votes(&[(Class::Head, 1), (Class::Torso, 1), (Class::UpperArms, 1)])
            ),
            head
        );
    }

    #[test]
    fn snap_goes_to_the_nearest_grid_pixel_inside_the_image() {
        assert_eq!(snap(7, 1, 10), 7);
        assert_eq!(snap(4, 3, 10), 3);
        assert_eq!(snap(5, 3, 10), 6);
        // 9 → 9 is on the grid of 3 and inside 10 pixels.
        assert_eq!(snap(9, 3, 10), 9);
        // 9 of 10 pixels with stride 4: 8 (12 is outside).
        assert_eq!(snap(9, 4, 10), 8);
        assert_eq!(snap(11, 4, 12), 8);
    }
}
