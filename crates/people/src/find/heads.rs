//! Geometry mode's heads: maxima of the top-view height map that are as large and as
//! compact as a head and stand on a continuous column of points down to the ground (in the
//! spirit of Munaro et al., ICRA 2012, without its HOG classifier); a neighbour's limb
//! lying on a head is left out of its test.

use crate::config::BoxesConfig;
use crate::find::candidates::{Cluster, VoxelHeights};
use crate::find::ground::xy_dist;
use bodyseg_core::math::Vec3;
use rustc_hash::{FxHashMap, FxHashSet};

/// Height of a head below its top, metres (crown to chin ≈ 0.22 m; the shoulders start
/// lower).
pub(crate) const HEAD_HEIGHT_M: f32 = 0.2;
/// Below this fraction of a person's height lie only their lower legs (knees are at
/// ≈ 0.28 of the height; the fingertips of a hanging arm at ≈ 0.38, a hand reaching to a
/// table higher): the column tests let the legs stand out to [`LEG_RADIUS_M`] there, and
/// the split seeds a person with their voxels this low.
pub(crate) const LOW_LEG_FRACTION: f32 = 0.3;
/// Horizontal radius around the head's vertical that holds the legs, metres (a stride
/// or a crouch puts a foot ≈ 0.35 m from it).
pub(crate) const LEG_RADIUS_M: f32 = 0.4;
/// Tops at least this high are taken to be people's when judging head compactness,
/// metres: a workcell robot arm on its base (≈ 1.4 m in bodyseg-synth) stays below.
const TALL_TOP_M: f32 = 1.5;
/// Extra head radius allowed to such tall tops, metres: hair, a tilted head, or a
/// neighbour's hand or arm on the head widen it, and only people reach that high.
const TALL_HEAD_SLACK_M: f32 = 0.1;
/// Two heads' tops are at least this far apart horizontally, metres (a head is ≈ 0.2 m
/// wide): a higher top closer than this always hides a lower one.
const MIN_HEAD_GAP_M: f32 = 0.25;
/// A branch leaving a head candidate sideways that rises this much above its top is
/// someone's limb reaching onto it, metres ([`reaching_limbs`]): a robot's links slope
/// down from a joint, an arm touching a crouching person's head rises to its owner's
/// shoulder; one voxel (5 cm), so that the jitter of voxel centroids does not count.
const REACH_RISE_M: f32 = 0.05;
/// A slice of a dense column holds at least this many voxels ([`dense_column`]): a
/// trunk's 10 cm slice holds several 5 cm voxels across, a robot's thin link one or two.
const DENSE_SLICE_VOXELS: usize = 4;
/// Share of dense slices below a head candidate for someone's limb touching it to be
/// left out of its head test ([`dense_column`]): a body fills its column all the way
/// down, so only about one slice in twenty may miss.
const MIN_DENSE_FILL: f32 = 0.95;
/// A top hidden by someone's limb lying on it ([`find_heads`]) is a head only at least
/// this high, metres: a crouching adult's head is 1.05–1.4 m high (bodyseg-synth), a
/// robot's base under its own upper arm ≈ 0.95 m.
const LIMB_HIDDEN_MIN_TOP_M: f32 = 1.0;
/// A head's blob (what is connected to its top within a head's height and is not someone
/// else's limb, [`find_heads`]) covers at least this much, m² (30 voxels at 5 cm): a head
/// covers more; a hand held out or a forearm before a chest, a compact top over its
/// owner's column too, less.
const MIN_HEAD_AREA_M2: f32 = 0.075;
/// Cell of the top-view height map heads are searched in, metres: a fraction of a head's
/// width (≈ 0.2 m), so that two heads [`MIN_HEAD_GAP_M`] apart fall in different cells.
const HEIGHT_MAP_CELL_M: f32 = 0.08;
/// Height of the slices of the column test, metres: two 5 cm voxels, so that a body's
/// surface leaves no slice empty wherever the cameras see it.
const COLUMN_SLICE_M: f32 = 0.1;

/// The heads of one cluster (geometry mode): cells of the top-view height map that are
/// the highest within `head_separation_m`, at least `geometry_min_height_m` high, as large
/// as a head ([`MIN_HEAD_AREA_M2`]), with a column of
/// points below them (`column_radius_m`, `min_column_fill`) reaching down to
/// `max_bottom_m`. Returns one voxel per head (its top), highest first.
pub(crate) fn find_heads(cluster: &Cluster, cfg: &BoxesConfig) -> Vec<u32> {
    let Cluster {
        graph,
        keep,
        members,
        at: VoxelHeights { centers, heights },
    } = *cluster;
    let inv = 1.0 / HEIGHT_MAP_CELL_M;
    let cell = |p: Vec3| [(p[0] * inv).floor() as i32, (p[1] * inv).floor() as i32];
    let mut map: FxHashMap<[i32; 2], u32> = FxHashMap::default();
    let higher = |a: u32, b: u32| {
        let (ha, hb) = (heights[a as usize], heights[b as usize]);
        ha > hb || (ha == hb && a < b)
    };
    for &i in members {
        let e = map.entry(cell(centers[i as usize])).or_insert(i);
        if higher(i, *e) {
            *e = i;
        }
    }
    let mut tops: Vec<u32> = map
        .values()
        .copied()
        .filter(|&v| heights[v as usize] >= cfg.min_top_m())
        .collect();
    tops.sort_by(|&a, &b| {
        heights[b as usize]
            .total_cmp(&heights[a as usize])
            .then(a.cmp(&b))
    });
    let r = (cfg.head_separation_m * inv).ceil() as i32;
    // The cluster's voxels in horizontal cells as wide as the widest column radius, so
    // that a column test reads the 3 × 3 cells around a top instead of the whole cluster
    // (a wall or a shelf has hundreds of candidate tops).
    let column_cell_m = LEG_RADIUS_M.max(cfg.column_radius_m);
    let column_key = |p: Vec3| {
        [
            (p[0] / column_cell_m).floor() as i32,
            (p[1] / column_cell_m).floor() as i32,
        ]
    };
    let mut columns: FxHashMap<[i32; 2], Vec<u32>> = FxHashMap::default();
    for &i in members {
        columns
            .entry(column_key(centers[i as usize]))
            .or_default()
            .push(i);
    }
    // Every voxel of the cluster within `column_cell_m` of `p` horizontally (and more).
    let column_near = |p: Vec3| {
        let k = column_key(p);
        let mut near = Vec::new();
        for dx in -1..=1 {
            for dy in -1..=1 {
                if let Some(vs) = columns.get(&[k[0] + dx, k[1] + dy]) {
                    near.extend_from_slice(vs);
                }
            }
        }
        near
    };
    let min_blob_voxels = MIN_HEAD_AREA_M2 / (cfg.voxel_m * cfg.voxel_m);
    let mut heads: Vec<u32> = Vec::new();
    for v in tops {
        let (p, c) = (centers[v as usize], cell(centers[v as usize]));
        // A higher top within `head_separation_m` hides this one unless it is a separate
        // peak: at least MIN_HEAD_GAP_M away and not joined to anything higher within a
        // head's height below this top (two heads leaning together, not a shoulder).
        // Closer tops hide it, unless they are someone's limb lying on it (see below).
        let mut hiders = Vec::new();
        let mut higher_near = false;
        for dx in -r..=r {
            for dy in -r..=r {
                if let Some(&o) = map.get(&[c[0] + dx, c[1] + dy])
                    && o != v
                    && higher(o, v)
                {
                    let d = xy_dist(centers[o as usize], p);
                    if d < MIN_HEAD_GAP_M {
                        hiders.push(o);
                    }
                    higher_near |= d < cfg.head_separation_m;
                }
            }
        }
        let h = heights[v as usize];
        // Every trace below, reaching_limbs' too, is about this candidate.
        let _candidate = tracing::trace_span!("head candidate", x = p[0], y = p[1], h).entered();
        // A limb lying on the head (a hand or forearm on its way up to its owner's
        // shoulder) neither hides it nor makes it part of something higher, far from
        // every head found so far; near one, such a top is that person's shoulder or
        // forearm under their own or a neighbour's hand. The cheap tests come first: most
        // tops are hidden (a head's or a shoulder's, near a head found before; a wall's).
        let may_be_under_limb = (LIMB_HIDDEN_MIN_TOP_M..=cfg.max_height_m).contains(&h)
            && heads
                .iter()
                .all(|&k| xy_dist(centers[k as usize], p) >= cfg.head_separation_m);
        let (percent, limit) = if h >= TALL_TOP_M {
            (75, cfg.max_head_radius_m + TALL_HEAD_SLACK_M)
        } else {
            (90, cfg.max_head_radius_m)
        };
        // Someone's limb touching the head from above (an arm reaching onto a crouching
        // person) is left out of the head test, but only where a body fills the column
        // below: a robot's joint stands on thin links and a pedestal. Such a limb lies
        // beyond `limit` of the top ([`reaching_limbs`]), so a top hidden by something
        // nearer, or over a column that is not filled, stays hidden: both are known
        // before the blob is grown.
        let limb_hidden = !hiders.is_empty();
        if limb_hidden
            && !(may_be_under_limb
                && hiders
                    .iter()
                    .all(|&o| xy_dist(centers[o as usize], p) > limit))
        {
            tracing::trace!(may_be_under_limb, "dropped: hidden by a higher top");
            continue;
        }
        let near = column_near(p);
        let dense = dense_column(&near, cluster.at, v, cfg) >= MIN_DENSE_FILL;
        if limb_hidden && !dense {
            tracing::trace!("dropped: hidden, column not dense");
            continue;
        }
        // Only what is connected to the top within the head's height belongs to this
        // head: a neighbour's head or a raised arm beside it (touching it only through
        // the shoulders, lower down) does not.
        let band = h - HEAD_HEIGHT_M;
        let blob = graph.grow(v, |j| {
            keep[j as usize]
                && heights[j as usize] >= band
                && xy_dist(centers[j as usize], p) < cfg.head_separation_m
        });
        let raised = higher_near && blob.iter().any(|&j| heights[j as usize] > h);
        if raised && !may_be_under_limb {
            tracing::trace!("dropped: raised");
            continue;
        }
        let under_limb = limb_hidden || raised;
        let foreign = if dense {
            reaching_limbs(cluster, &blob, v, limit, cfg)
        } else {
            FxHashSet::default()
        };
        if under_limb {
            // What hides the top, and all of the blob higher than it, must be such a limb.
            let limb = |j: &u32| foreign.contains(j);
            if !hiders.iter().all(limb) || blob.iter().any(|j| heights[*j as usize] > h && !limb(j))
            {
                tracing::trace!("dropped: hidden by something higher that is not a limb");
                continue;
            }
            tracing::trace!("the limb lying on it does not hide it");
        }
        // Head test: a head is a compact top. A robot arm's or a shelf's top continues
        // sideways (cylinders sloping down from a joint).
        let mut near_top: Vec<f32> = blob
            .iter()
            .filter(|j| !foreign.contains(j))
            .map(|&j| xy_dist(centers[j as usize], p))
            .collect();
        near_top.sort_by(f32::total_cmp);
        // A percentile, so that a hand raised to the face or a stray voxel does not count:
        // the 90th below TALL_TOP_M; above it (only people reach there) the 75th, as a
        // neighbour's hand or pointing arm touching the head may cover a quarter of it.
        let spread = near_top
            .get(near_top.len() * percent / 100)
            .copied()
            .unwrap_or(0.0);
        if spread > limit {
            tracing::trace!(spread, "dropped: not compact");
            continue;
        }
        // A head is a head's size: a hand or a forearm held before a chest or handed over
        // is a compact top too, over a body's column (its owner's), but smaller.
        if (near_top.len() as f32) < min_blob_voxels {
            tracing::trace!(voxels = near_top.len(), "dropped: smaller than a head");
            continue;
        }
        let (fill, lowest) = column_fill(&near, cluster.at, v, cfg);
        tracing::trace!(fill, lowest, blob = near_top.len(), spread, "tested");
        if fill >= cfg.min_column_fill && lowest <= cfg.max_bottom_m {
            heads.push(v);
        }
    }
    heads
}

/// The voxels of a head candidate's blob (`blob`, grown from the top `top`) that belong to
/// someone else's limb reaching down onto it: beyond `limit` of the top's vertical, joined
/// outward (above the blob's band, within `max_reach_m`) to anything higher than the top.
/// A robot's top continues sideways only downwards (links sloping down from a joint); an
/// arm touching a crouching person's head rises to its owner's shoulder.
fn reaching_limbs(
    cluster: &Cluster,
    blob: &[u32],
    top: u32,
    limit: f32,
    cfg: &BoxesConfig,
) -> FxHashSet<u32> {
    let Cluster {
        graph,
        keep,
        at: VoxelHeights { centers, heights },
        ..
    } = *cluster;
    let p = centers[top as usize];
    let h = heights[top as usize];
    let band = h - HEAD_HEIGHT_M;
    let xy = |j: u32| xy_dist(centers[j as usize], p);
    let mut seen: FxHashSet<u32> = FxHashSet::default();
    let mut foreign = FxHashSet::default();
    for &s in blob {
        if xy(s) <= limit || seen.contains(&s) {
            continue;
        }
        let branch = graph.grow(s, |j| {
            keep[j as usize] && heights[j as usize] >= band && {
                let d = xy(j);
                d > limit && d <= cfg.max_reach_m
            }
        });
        let rises = branch
            .iter()
            .any(|&j| heights[j as usize] > h + REACH_RISE_M);
        seen.extend(branch.iter().copied());
        if rises {
            tracing::trace!(
                voxels = branch.len(),
                "a limb reaching onto it is left out of its head test"
            );
            foreign.extend(branch);
        }
    }
    foreign
}

/// The fraction of the [`COLUMN_SLICE_M`] slices between [`LOW_LEG_FRACTION`] of the
/// height of `top` and `top` that hold at least [`DENSE_SLICE_VOXELS`] of `voxels` within
/// `column_radius_m` of its vertical: a person's trunk, neck and head fill every slice; a
/// robot's joint stands on a thin sloping link (one or two voxels a slice). `voxels` are
/// the cluster's, or those of its cells around the top (`column_near` in [`find_heads`]).
fn dense_column(voxels: &[u32], at: VoxelHeights, top: u32, cfg: &BoxesConfig) -> f32 {
    let low = LOW_LEG_FRACTION * at.heights[top as usize];
    let (counts, _) = column_slices(voxels, at, top, low, |_| cfg.column_radius_m);
    counts.iter().filter(|&&c| c >= DENSE_SLICE_VOXELS).count() as f32 / counts.len() as f32
}

/// The column test of the head candidate `top` (geometry mode): the fraction of the
/// [`COLUMN_SLICE_M`] slices between the ground and the top that hold one of `voxels` (as
/// in [`dense_column`]) within `column_radius_m` of the top's vertical (below
/// [`LOW_LEG_FRACTION`] of the top's height: within [`LEG_RADIUS_M`]), and the lowest such
/// voxel's height.
fn column_fill(voxels: &[u32], at: VoxelHeights, top: u32, cfg: &BoxesConfig) -> (f32, f32) {
    // The lower legs may stand farther out: a crouch puts the feet ≈ 0.3 m behind the
    // head, a stride ahead of it; only the column above them must be narrow.
    let legs_below = LOW_LEG_FRACTION * at.heights[top as usize];
    let (counts, lowest) = column_slices(voxels, at, top, cfg.ground_tol_m, |hj| {
        if hj < legs_below {
            LEG_RADIUS_M.max(cfg.column_radius_m)
        } else {
            cfg.column_radius_m
        }
    });
    let fill = counts.iter().filter(|&&c| c > 0).count() as f32 / counts.len() as f32;
    (fill, lowest)
}

/// How many of `voxels` lie in each [`COLUMN_SLICE_M`] slice of the column below `top`,
/// from height `from_m` up to the top (at least one slice), counting those at least
/// `from_m` high within `radius(height)` of the top's vertical; and the lowest of them.
fn column_slices(
    voxels: &[u32],
    at: VoxelHeights,
    top: u32,
    from_m: f32,
    radius: impl Fn(f32) -> f32,
) -> (Vec<usize>, f32) {
    let VoxelHeights { centers, heights } = at;
    let p = centers[top as usize];
    let h = heights[top as usize];
    let slices = ((h - from_m) / COLUMN_SLICE_M).ceil().max(1.0) as usize;
    let mut counts = vec![0usize; slices];
    let mut lowest = f32::INFINITY;
    for &j in voxels {
        let (q, hj) = (centers[j as usize], heights[j as usize]);
        if hj >= from_m && xy_dist(q, p) <= radius(hj) {
            lowest = lowest.min(hj);
            if let Some(c) = counts.get_mut(((hj - from_m) / COLUMN_SLICE_M) as usize) {
                *c += 1;
            }
        }
    }
    (counts, lowest)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Voxel centres at (`x`, 0, z) for every z in `z_m`.
    fn line(out: &mut Vec<Vec3>, x: f32, z_m: &[f32]) {
        out.extend(z_m.iter().map(|&z| [x, 0.0, z]));
    }

    /// `column_fill` of the highest of `centers` (heights: z), over all of them.
    fn fill_of(centers: &[Vec3]) -> (f32, f32) {
        let heights: Vec<f32> = centers.iter().map(|p| p[2]).collect();
        let top = (0..centers.len() as u32)
            .max_by(|&a, &b| heights[a as usize].total_cmp(&heights[b as usize]))
            .expect("voxels");
        let all: Vec<u32> = (0..centers.len() as u32).collect();
        let at = VoxelHeights {
            centers,
            heights: &heights,
        };
        column_fill(&all, at, top, &BoxesConfig::default())
    }

    #[test]
    fn column_counts_feet_beside_the_head_but_not_a_trunk_beside_it() {
        // Heights at the middle of the 10 cm slices above ground_tol_m (0.05 m), the top
        // at 1.22 m: 12 slices. A crouch: head and trunk above the knees at x = 0
        // (0.5–1.22 m: 8 slices), the lower legs 0.3 m behind (0.1–0.3 m: 3 slices),
        // beyond `column_radius_m`, within a leg's reach.
        let trunk = [0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2, 1.22];
        let mut centers = Vec::new();
        line(&mut centers, 0.0, &trunk);
        line(&mut centers, 0.3, &[0.1, 0.2, 0.3]);
        let (fill, lowest) = fill_of(&centers);
        // Counting only the column within 0.2 m: 8 of 12 slices (0.67 < min_column_fill),
        // lowest 0.5 m (> max_bottom_m): the crouching person had no head.
        assert_eq!(fill, 11.0 / 12.0);
        assert_eq!(lowest, 0.1);
        // Something 0.3 m beside the top above the legs' height (a neighbour's trunk)
        // does not fill the column.
        let mut centers = Vec::new();
        line(&mut centers, 0.0, &[1.1, 1.2, 1.22]);
        line(&mut centers, 0.3, &[0.5, 0.6, 0.7, 0.8, 0.9, 1.0]);
        let (fill, lowest) = fill_of(&centers);
        assert_eq!(fill, 2.0 / 12.0);
        assert_eq!(lowest, 1.1);
    }
}
