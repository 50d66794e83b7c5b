//! Colours for geometry mode's split: each voxel's chromaticity, histograms of the
//! colours in the column below each head (where nothing but that person stands), and from
//! them which voxels are of a person's colours ([`person_colored`]) or of the colours only
//! one person wears ([`worn_by_one`]).

use crate::find::ground::xy_dist;
use crate::voxel::Voxels;
use bodyseg_core::math::{CHROMA_BINS, Vec3, chroma_bin, near_chroma_bins, srgb_to_linear};

/// A colour is one person's only ([`worn_by_one`]) when every other person's column holds
/// less than this fraction of it (with neighbouring bins): an arm reaching across a
/// neighbour's column adds its sleeve there, a few voxels of the column's.
const OTHER_WEARS_DENSITY: f32 = 0.02;
/// A colour is a person's when at least this fraction of the coloured voxels in the column
/// below their head share its chromaticity bin or a neighbouring one ([`person_colored`]):
/// more than a stray voxel's share, less than a hand's or a collar's.
const PERSON_COLOR_DENSITY: f32 = 0.03;

/// Per voxel, its points' mean colour as a linear-RGB chromaticity bin ([`chroma_bin`]);
/// `None` where it is too dark to tell (black: no colour).
pub(crate) fn voxel_chroma(all: &Voxels, colors: &[[u8; 3]]) -> Vec<Option<u16>> {
    // sRGB to linear, once per byte value.
    let lin: Vec<f32> = (0..=255).map(srgb_to_linear).collect();
    let mut sums = vec![[0f32; 3]; all.centers.len()];
    for (&i, &v) in all.points.iter().zip(&all.point_voxel) {
        if let Some(c) = colors.get(i as usize) {
            for a in 0..3 {
                sums[v as usize][a] += lin[usize::from(c[a])];
            }
        }
    }
    sums.iter()
        .zip(&all.counts)
        .map(|(s, &n)| {
            let total = s[0] + s[1] + s[2];
            // Darker than ~sRGB 60 on average: shading, not a colour.
            if total < 0.045 * 3.0 * n as f32 {
                return None;
            }
            Some(chroma_bin(*s) as u16)
        })
        .collect()
}

/// Per voxel of `cluster` (indexed by voxel): whether the part that is nobody's spreads
/// into it at the split's `FOREIGN_COLOR_SCALE` (and pays its `COLOR_EDGE_PENALTY_M` to
/// enter it): its colour is one of a person's — at least [`PERSON_COLOR_DENSITY`] of the coloured
/// voxels of their column (`people`, [`column_colors`]: head, shirt, trousers, where
/// nothing but the person stands) share its chromaticity bin or a neighbouring one — and
/// that person wears its very bin at least as much as what the part that is nobody's
/// claimed on positions alone (`claimed`) does, as shares of each one's coloured voxels.
/// That part is mostly the robot, so its colours are the robot's; an arm it took along a
/// link is a small share of it. A sleeve or a hand reaching along a robot link then stays
/// its owner's, while the link, of the robot's colour, is still claimed from the pedestal
/// at the split's `NOBODY_LENGTH_SCALE`. Where the robot wears a person's colour more than
/// they do the split is as without colours.
///
/// The very bin is compared, not its neighbours: a colour a bin from both the person's and
/// the robot's (a grey shirt beside grey joints, a shade of an orange robot beside an
/// orange shirt) goes to whichever wears that very bin more.
pub(crate) fn person_colored(
    chroma: &[Option<u16>],
    cluster: &[u32],
    people: &[ChromaHist],
    claimed: &[u32],
) -> Vec<bool> {
    let nobody = ChromaHist::of(chroma, claimed.iter().copied());
    let mut out = vec![false; chroma.len()];
    for &j in cluster {
        if let Some(b) = chroma[j as usize] {
            let robot = nobody.share(b);
            // At least as much: a colour neither wears in its very bin, a bin from a
            // person's (a hand a shade off the face), is the person's.
            out[j as usize] = people
                .iter()
                .any(|p| p.near_at_least(b, PERSON_COLOR_DENSITY) && p.share(b) >= robot);
        }
    }
    out
}

/// A histogram of voxels' chromaticity bins ([`voxel_chroma`]; voxels without a colour
/// are not counted).
pub(crate) struct ChromaHist {
    bins: Vec<u32>,
    total: u32,
}

impl ChromaHist {
    fn of(chroma: &[Option<u16>], members: impl Iterator<Item = u32>) -> ChromaHist {
        let mut bins = vec![0u32; CHROMA_BINS * CHROMA_BINS];
        let mut total = 0u32;
        for j in members {
            if let Some(b) = chroma[j as usize] {
                bins[usize::from(b)] += 1;
                total += 1;
            }
        }
        ChromaHist { bins, total }
    }

    /// Whether at least `density` of the voxels lie within a bin of `b`.
    fn near_at_least(&self, b: u16, density: f32) -> bool {
        let n: u32 = near_chroma_bins(usize::from(b)).map(|k| self.bins[k]).sum();
        self.total > 0 && n as f32 >= density * self.total as f32
    }

    /// The share of the voxels in the very bin `b`.
    fn share(&self, b: u16) -> f32 {
        if self.total == 0 {
            0.0
        } else {
            self.bins[usize::from(b)] as f32 / self.total as f32
        }
    }
}

/// The colours of the column below each of `heads` (within `column_radius_m` of its
/// vertical, among `cluster`): where nothing but that person stands (head, shirt, trousers).
pub(crate) fn column_colors(
    chroma: &[Option<u16>],
    cluster: &[u32],
    heads: &[u32],
    centers: &[Vec3],
    column_radius_m: f32,
) -> Vec<ChromaHist> {
    heads
        .iter()
        .map(|&h| {
            let top = centers[h as usize];
            let column = cluster
                .iter()
                .copied()
                .filter(|&j| xy_dist(centers[j as usize], top) <= column_radius_m);
            ChromaHist::of(chroma, column)
        })
        .collect()
}

/// Per voxel of `cluster` (indexed by voxel): the one person (index into `people`, the
/// colours of each head's column, [`column_colors`]) whose colour it is, `None` for none
/// or several: at least [`PERSON_COLOR_DENSITY`] of the coloured voxels of their column
/// share its chromaticity bin or a neighbouring one, and less than
/// [`OTHER_WEARS_DENSITY`] of every other person's column do. A sleeve reaching a
/// neighbour's chest is then its owner's colour
/// ([`split_people`](crate::find::split::split_people)).
pub(crate) fn worn_by_one(
    chroma: &[Option<u16>],
    cluster: &[u32],
    people: &[ChromaHist],
) -> Vec<Option<u32>> {
    let mut out = vec![None; chroma.len()];
    for &j in cluster {
        if let Some(b) = chroma[j as usize] {
            let mut wearers =
                (0..people.len()).filter(|&k| people[k].near_at_least(b, PERSON_COLOR_DENSITY));
            if let (Some(k), None) = (wearers.next(), wearers.next())
                && people
                    .iter()
                    .enumerate()
                    .all(|(o, p)| o == k || !p.near_at_least(b, OTHER_WEARS_DENSITY))
            {
                out[j as usize] = Some(k as u32);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_a_person_s_colors_the_robot_does_not_wear_slow_the_robot_s_spread() {
        let bin = |r: usize, g: usize| Some((r * CHROMA_BINS + g) as u16);
        // A person at x = 0 (head 0, then 20 voxels in the column: 10 shirt, 10 skin) and
        // beside them, 1 m away, a robot of 40 voxels: 39 orange, one (under the density)
        // in the shirt's colour.
        let (shirt, skin, orange) = (bin(15, 15), bin(25, 17), bin(32, 16));
        let mut centers = vec![[0.0, 0.0, 1.8]];
        let mut chroma = vec![skin];
        for k in 0..20 {
            centers.push([0.05, 0.0, 1.6 - 0.05 * k as f32]);
            chroma.push(if k < 10 { shirt } else { skin });
        }
        for k in 0..40 {
            centers.push([1.0, 0.0, 0.1 + 0.025 * k as f32]);
            chroma.push(if k == 0 { shirt } else { orange });
        }
        // Then the voxels to judge, all out of every column and seed: a sleeve (shirt), a
        // hand (a bin beside the skin's), a robot link (orange), one too dark, one of a
        // colour nobody wears.
        let judged = [shirt, bin(26, 17), orange, None, bin(10, 30)];
        for c in judged {
            centers.push([0.5, 0.0, 1.2]);
            chroma.push(c);
        }
        let cluster: Vec<u32> = (0..centers.len() as u32).collect();
        let robot: Vec<u32> = (21..61).collect();
        // Which of the judged voxels (61..) are the person's colour, the person the only seed.
        let judged_colored = |chroma: &[Option<u16>]| {
            let columns = column_colors(chroma, &cluster, &[0], &centers, 0.2);
            person_colored(chroma, &cluster, &columns, &robot)[61..].to_vec()
        };
        assert_eq!(judged_colored(&chroma), &[true, true, false, false, false]);
        // The scene with the person in `shirt` (their column's and the judged sleeve) and
        // the robot's voxels `part` (and the judged link) in `robot_color`.
        let dressed = |shirt, part: std::ops::Range<usize>, robot_color| {
            let mut c = chroma.clone();
            c[1..11].fill(shirt);
            c[part].fill(robot_color);
            c[61] = shirt;
            c[63] = robot_color;
            c
        };
        // A shirt of the robot's colour: nothing is slowed any more than without colours.
        let same = dressed(orange, 0..0, orange);
        assert_eq!(judged_colored(&same), &[false, true, false, false, false]);
        // Nothing claimed with a colour (a dark pedestal alone): a person's colours slow it.
        let dark: Vec<Option<u16>> = (0..chroma.len())
            .map(|j| {
                if robot.contains(&(j as u32)) {
                    None
                } else {
                    chroma[j]
                }
            })
            .collect();
        assert_eq!(judged_colored(&dark), &[true, true, false, false, false]);
        // A grey shirt one bin from the robot's grey joints (half its voxels): the sleeve
        // is still the person's colour, the joints still the robot's.
        let grey = dressed(bin(15, 17), 21..41, bin(15, 16));
        assert_eq!(judged_colored(&grey), &[true, true, false, false, false]);
        // An orange shirt a bin from the robot's orange, and the robot's shade of it (5% of
        // the robot, a bin from both): the shade is the robot's, which wears its very bin
        // more than the person. (When a colour was the robot's only from 10% of its part
        // on, the shade was the person's.)
        let shaded = dressed(bin(33, 15), 21..23, bin(32, 15));
        assert_eq!(judged_colored(&shaded), &[true, true, false, false, false]);
    }

    #[test]
    fn a_color_only_one_person_wears_is_theirs() {
        let bin = |r: usize, g: usize| Some((r * CHROMA_BINS + g) as u16);
        let (skin, red, blue, grey) = (bin(30, 12), bin(40, 10), bin(8, 12), bin(15, 17));
        // Two people 1 m apart, each a column of 40 voxels: 10 skin, then 30 of their shirt
        // (red, blue), in the red one's 3 of them grey (7.5%: theirs), in the blue one's 1
        // (2.5%: under PERSON_COLOR_DENSITY, over OTHER_WEARS_DENSITY).
        let mut centers = vec![[0.0, 0.0, 1.8], [1.0, 0.0, 1.8]];
        let mut chroma = vec![skin, skin];
        for (x, shirt) in [(0.0, red), (1.0, blue)] {
            for k in 0..40 {
                centers.push([x, 0.0, 1.75 - 0.04 * k as f32]);
                chroma.push(match k {
                    0..10 => skin,
                    10..13 if x == 0.0 => grey,
                    39 if x == 1.0 => grey,
                    _ => shirt,
                });
            }
        }
        // Judged, between them and in neither column: a red sleeve, a blue one, a hand,
        // something grey (both wear a little), a colour nobody wears, one too dark.
        for c in [red, blue, skin, grey, bin(20, 30), None] {
            centers.push([0.5, 0.0, 1.3]);
            chroma.push(c);
        }
        let cluster: Vec<u32> = (0..centers.len() as u32).collect();
        let got = worn_by_one(
            &chroma,
            &cluster,
            &column_colors(&chroma, &cluster, &[0, 1], &centers, 0.2),
        );
        assert_eq!(&got[82..], &[Some(0), Some(1), None, None, None, None]);
        // One person: every colour they wear is theirs alone, the grey too.
        let got = worn_by_one(
            &chroma,
            &cluster,
            &column_colors(&chroma, &cluster, &[0], &centers, 0.2),
        );
        assert_eq!(&got[82..], &[Some(0), None, Some(0), Some(0), None, None]);
    }
}
