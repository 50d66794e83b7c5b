//! A frame's clouds as the `Points3D` batches that [`crate::ViewWriter`] logs, with the
//! positions gathered once.
//!
//! The projected and the refined cloud are the same points (same positions, same order)
//! with other labels, and each layer logs its known and its unknown points apart. The
//! points are gathered once, into one Arrow array, in the order of four groups:
//!
//! ```text
//! C: known only in refined | A: known in both | B: known only in projected | D: unknown in both
//! refined known   = C ∪ A   projected known = A ∪ B   refined unknown = B ∪ D
//! projected unknown = C ∪ D: a slice when C or D is empty, else its own copy
//! ```
//!
//! so that every other entity is a zero-copy slice of that array (Arrow IPC writes a
//! slice's values only). A missing layer counts as all unknown: one layer alone is its
//! known then its unknown points. The clusters take the whole array, their colours in the
//! same order.

use crate::paths;
use bodyseg_core::Label;
use bodyseg_core::math::Vec3;
use re_sdk::external::arrow::array::{
    Array, ArrayRef, FixedSizeListArray, Float32Array, UInt16Array,
};
use re_sdk::external::arrow::buffer::ScalarBuffer;
use re_sdk::external::arrow::datatypes::{DataType, Field};
use re_sdk_types::datatypes::Rgba32;
use std::ops::Range;
use std::sync::Arc;

/// What colours the points of a batch.
#[derive(Debug)]
pub(crate) enum Paint {
    /// One class id per point.
    Classes(ArrayRef),
    /// One class id for all: unknown (255).
    Unknown,
    /// One colour per point (the clusters).
    Colors(Vec<Rgba32>),
}

/// One `Points3D` to log.
#[derive(Debug)]
pub(crate) struct CloudBatch {
    /// Its entity path ([`paths`]).
    pub(crate) entity: &'static str,
    /// A `Position3D` batch (FixedSizeList of 3 f32).
    pub(crate) positions: ArrayRef,
    pub(crate) paint: Paint,
}

/// One cloud's points, known or not per layer; `None`: the layer is not logged.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Layers<'a> {
    pub(crate) positions_m: &'a [Vec3],
    pub(crate) projected: Option<&'a [Label]>,
    pub(crate) refined: Option<&'a [Label]>,
    /// One cluster (person, cluster) or noise per point.
    pub(crate) clusters: Option<&'a [Option<(u32, u32)>]>,
}

/// Group codes: bit 0 = known in projected, bit 1 = known in refined.
const D: usize = 0;
const B: usize = 1;
const C: usize = 2;
const A: usize = 3;

/// Calls `f(group, points)` for each run of points of one group, in order.
fn for_each_run(codes: &[u8], mut f: impl FnMut(usize, Range<usize>)) {
    let mut i = 0;
    while let Some(&g) = codes.get(i) {
        // Eight codes at a time while they all equal g, then one by one.
        let eight = u64::from_ne_bytes([g; 8]);
        let rest = &codes[i..];
        let whole = rest
            .chunks_exact(8)
            .position(|c| u64::from_ne_bytes(c.try_into().expect("8 bytes")) != eight)
            .unwrap_or(rest.len() / 8)
            * 8;
        let len = whole
            + rest[whole..]
                .iter()
                .position(|&c| c != g)
                .unwrap_or(rest.len() - whole);
        f(usize::from(g & 3), i..i + len);
        i += len;
    }
}

/// The batches of `layers` (lengths checked by the caller: labels and clusters as long as
/// the positions): known and unknown per present layer, then the clusters when given.
/// `cluster_color` colours a cluster.
pub(crate) fn cloud_batches(
    layers: Layers<'_>,
    cluster_color: impl Fn(Option<(u32, u32)>) -> Rgba32,
) -> Vec<CloudBatch> {
    let Layers {
        positions_m: xyz,
        projected,
        refined,
        clusters,
    } = layers;
    let n = xyz.len();
    debug_assert!(projected.is_none_or(|l| l.len() == n));
    debug_assert!(refined.is_none_or(|l| l.len() == n));
    debug_assert!(clusters.is_none_or(|c| c.len() == n));
    // Each point's group, then the runs of each group (labels come in runs: a camera's
    // pixels row by row).
    let mut codes = vec![0u8; n];
    for (bit, labels) in [(1, projected), (2, refined)] {
        for (g, l) in codes.iter_mut().zip(labels.unwrap_or_default()) {
            *g |= if l.is_unknown() { 0 } else { bit };
        }
    }
    let mut runs: [Vec<Range<usize>>; 4] = Default::default();
    for_each_run(&codes, |g, run| runs[g].push(run));
    drop(codes);
    let size = |g: usize| runs[g].iter().map(ExactSizeIterator::len).sum::<usize>();
    let (a, b, c, d) = (size(A), size(B), size(C), size(D));
    // Gather, group by group in the order C, A, B, D, each run appended as a block: the
    // positions; each layer's class ids, all its points in that order (its known points are
    // a slice: IPC writes only the slice); the clusters' colours. Appending, nothing is
    // written twice (a buffer filled in place is zeroed first: 5.3 M of the gather's 14.6 M
    // instructions a frame, docs/notes/2026-12-02-rerun.md, 2026-12-04b).
    let mut out: Vec<f32> = Vec::with_capacity(n * 3);
    let mut projected_ids = projected.map(|_| Vec::<u16>::with_capacity(n));
    let mut refined_ids = refined.map(|_| Vec::<u16>::with_capacity(n));
    let mut colors = clusters.map(|_| Vec::<Rgba32>::with_capacity(n));
    let id = |l: &Label| u16::from(l.id());
    for g in [C, A, B, D] {
        for run in &runs[g] {
            out.extend_from_slice(xyz[run.clone()].as_flattened());
            if let (Some(ids), Some(l)) = (&mut projected_ids, projected) {
                ids.extend(l[run.clone()].iter().map(id));
            }
            if let (Some(ids), Some(l)) = (&mut refined_ids, refined) {
                ids.extend(l[run.clone()].iter().map(id));
            }
            if let (Some(colors), Some(c)) = (&mut colors, clusters) {
                colors.extend(c[run.clone()].iter().map(|c| cluster_color(*c)));
            }
        }
    }
    let projected_ids = projected_ids.map(UInt16Array::from);
    let refined_ids = refined_ids.map(UInt16Array::from);
    let all = positions(out);
    let mut batches = Vec::with_capacity(5);
    if let Some(ids) = projected_ids {
        batches.push(CloudBatch {
            entity: paths::PROJECTED,
            positions: all.slice(c, a + b),
            paint: Paint::Classes(Arc::new(ids.slice(c, a + b))),
        });
        let unknown = if c == 0 || d == 0 || a + b == 0 {
            // C ∪ D is contiguous: D alone, C alone, or C then D.
            all.slice(if c == 0 { a + b } else { 0 }, c + d)
        } else {
            // C and D apart (A ∪ B between them): their own copy.
            let flat = flat_values(&all);
            let mut xyz = Vec::with_capacity((c + d) * 3);
            xyz.extend_from_slice(&flat[..c * 3]);
            xyz.extend_from_slice(&flat[(c + a + b) * 3..]);
            positions(xyz)
        };
        batches.push(CloudBatch {
            entity: paths::PROJECTED_UNKNOWN,
            positions: unknown,
            paint: Paint::Unknown,
        });
    }
    if let Some(ids) = refined_ids {
        batches.push(CloudBatch {
            entity: paths::REFINED,
            positions: all.slice(0, c + a),
            paint: Paint::Classes(Arc::new(ids.slice(0, c + a))),
        });
        batches.push(CloudBatch {
            entity: paths::REFINED_UNKNOWN,
            positions: all.slice(c + a, b + d),
            paint: Paint::Unknown,
        });
    }
    if let Some(colors) = colors {
        batches.push(CloudBatch {
            entity: paths::CLUSTERS,
            positions: all,
            paint: Paint::Colors(colors),
        });
    }
    batches
}

/// Flat x, y, z per point as the Arrow array of a `Position3D` batch, without a copy.
fn positions(xyz_m: Vec<f32>) -> ArrayRef {
    debug_assert_eq!(xyz_m.len() % 3, 0);
    let xyz = Float32Array::new(ScalarBuffer::from(xyz_m), None);
    // The datatype of `Position3D` (`Vec3D`): a non-nullable `item` of f32, 3 per point.
    let item = Arc::new(Field::new("item", DataType::Float32, false));
    Arc::new(FixedSizeListArray::new(item, 3, Arc::new(xyz), None))
}

/// The flat x, y, z values of a [`positions`] array (or of its slice).
fn flat_values(positions: &ArrayRef) -> &[f32] {
    let list = positions
        .as_any()
        .downcast_ref::<FixedSizeListArray>()
        .expect("a Position3D batch");
    let values = list
        .values()
        .as_any()
        .downcast_ref::<Float32Array>()
        .expect("f32 values");
    // A FixedSizeListArray's slice slices its values: they are the slice's own.
    values.values()
}

#[cfg(test)]
mod tests {
    use super::*;
    use re_sdk::external::arrow::array::AsArray;
    use re_sdk::external::arrow::datatypes::UInt16Type;

    const U: u8 = Label::UNKNOWN_ID;

    fn labels(ids: &[u8]) -> Vec<Label> {
        ids.iter().map(|&i| Label::from_id_or_unknown(i)).collect()
    }

    /// Point i at x = i, so that a batch's points name the input's indices.
    fn cloud(n: usize) -> Vec<Vec3> {
        (0..n).map(|i| [i as f32, -(i as f32), 0.5]).collect()
    }

    fn color(c: Option<(u32, u32)>) -> Rgba32 {
        c.map_or(Rgba32(0), |(p, k)| Rgba32(p * 100 + k))
    }

    fn values(b: &CloudBatch) -> &Float32Array {
        b.positions
            .as_fixed_size_list()
            .values()
            .as_primitive::<re_sdk::external::arrow::datatypes::Float32Type>()
    }

    /// The input indices of a batch's points (checking their y and z too).
    fn indices(b: &CloudBatch) -> Vec<usize> {
        values(b)
            .values()
            .chunks(3)
            .map(|p| {
                assert_eq!((p[1], p[2]), (-p[0], 0.5), "{}: a point torn", b.entity);
                p[0] as usize
            })
            .collect()
    }

    /// The start of the allocation that holds a batch's positions.
    fn allocation(b: &CloudBatch) -> *const u8 {
        values(b).values().inner().data_ptr().as_ptr()
    }

    fn ids(b: &CloudBatch) -> Vec<u16> {
        match &b.paint {
            Paint::Classes(ids) => ids.as_primitive::<UInt16Type>().values().to_vec(),
            Paint::Unknown => vec![u16::from(U); b.positions.len()],
            Paint::Colors(_) => panic!("{}: colours, not classes", b.entity),
        }
    }

    fn batch<'a>(batches: &'a [CloudBatch], entity: &str) -> &'a CloudBatch {
        batches
            .iter()
            .find(|b| b.entity == entity)
            .unwrap_or_else(|| panic!("no {entity}"))
    }

    fn entities(batches: &[CloudBatch]) -> Vec<&'static str> {
        batches.iter().map(|b| b.entity).collect()
    }

    fn sorted(mut v: Vec<usize>) -> Vec<usize> {
        v.sort_unstable();
        v
    }

    /// Each layer's known and unknown batches hold exactly its known and unknown points
    /// (as sets: the order is the gather's), with their class ids point by point.
    fn check_layer(batches: &[CloudBatch], known: &str, unknown: &str, l: &[Label]) {
        let k = batch(batches, known);
        let got: Vec<(usize, u16)> = indices(k).into_iter().zip(ids(k)).collect();
        assert_eq!(got.len(), k.positions.len());
        for &(i, id) in &got {
            assert_eq!(id, u16::from(l[i].id()), "{known}: point {i}'s class id");
        }
        let want_known: Vec<usize> = (0..l.len()).filter(|&i| !l[i].is_unknown()).collect();
        let want_unknown: Vec<usize> = (0..l.len()).filter(|&i| l[i].is_unknown()).collect();
        assert_eq!(
            sorted(got.iter().map(|g| g.0).collect()),
            want_known,
            "{known}"
        );
        let u = batch(batches, unknown);
        assert!(
            matches!(u.paint, Paint::Unknown),
            "{unknown}: one class id 255"
        );
        assert_eq!(sorted(indices(u)), want_unknown, "{unknown}");
    }

    fn check_layers(batches: &[CloudBatch], p: &[Label], r: &[Label]) {
        check_layer(batches, paths::PROJECTED, paths::PROJECTED_UNKNOWN, p);
        check_layer(batches, paths::REFINED, paths::REFINED_UNKNOWN, r);
    }

    /// The batches of both layers (and of these clusters) on points 0..n.
    fn both(p: &[Label], r: &[Label], clusters: Option<&[Option<(u32, u32)>]>) -> Vec<CloudBatch> {
        let xyz = cloud(p.len());
        cloud_batches(
            Layers {
                positions_m: &xyz,
                projected: Some(p),
                refined: Some(r),
                clusters,
            },
            color,
        )
    }

    #[test]
    fn groups_are_ordered_c_a_b_d_and_layers_are_slices() {
        // Groups per point: A = known in both, B = projected only, C = refined only, D = none.
        let p = labels(&[1, U, 2, U, 3, 4, U, 0]); //  A C B D B A C A
        let r = labels(&[5, 6, U, U, U, 1, 2, 3]);
        let clusters: Vec<Option<(u32, u32)>> = (0..8).map(|i| Some((1, i))).collect();
        let batches = both(&p, &r, Some(&clusters));
        assert_eq!(
            entities(&batches),
            [
                paths::PROJECTED,
                paths::PROJECTED_UNKNOWN,
                paths::REFINED,
                paths::REFINED_UNKNOWN,
                paths::CLUSTERS
            ]
        );
        // The whole array: C (1, 6), A (0, 5, 7), B (2, 4), D (3), each in input order.
        let all = batch(&batches, paths::CLUSTERS);
        assert_eq!(indices(all), [1, 6, 0, 5, 7, 2, 4, 3]);
        let Paint::Colors(colors) = &all.paint else {
            panic!("clusters: colours")
        };
        let want: Vec<Rgba32> = indices(all).iter().map(|&i| color(clusters[i])).collect();
        assert_eq!(*colors, want, "the colours permuted as the points");
        assert_eq!(indices(batch(&batches, paths::REFINED)), [1, 6, 0, 5, 7]);
        assert_eq!(indices(batch(&batches, paths::PROJECTED)), [0, 5, 7, 2, 4]);
        assert_eq!(indices(batch(&batches, paths::REFINED_UNKNOWN)), [2, 4, 3]);
        assert_eq!(
            indices(batch(&batches, paths::PROJECTED_UNKNOWN)),
            [1, 6, 3]
        );
        check_layers(&batches, &p, &r);
        // Every entity is a slice of the one array, but the projected unknown points (C
        // not empty): their own copy.
        let one = allocation(all);
        for b in &batches {
            let shared = allocation(b) == one;
            assert_eq!(shared, b.entity != paths::PROJECTED_UNKNOWN, "{}", b.entity);
        }
    }

    #[test]
    fn without_c_every_entity_is_a_slice_of_one_array() {
        let p = labels(&[1, U, 2, U, 3, 4]); // A D B D A B
        let r = labels(&[5, U, U, U, 6, U]);
        let batches = both(&p, &r, None);
        assert_eq!(batches.len(), 4, "no clusters unless given");
        assert_eq!(indices(batch(&batches, paths::REFINED)), [0, 4]);
        assert_eq!(indices(batch(&batches, paths::PROJECTED)), [0, 4, 2, 5]);
        assert_eq!(indices(batch(&batches, paths::PROJECTED_UNKNOWN)), [1, 3]);
        assert_eq!(
            indices(batch(&batches, paths::REFINED_UNKNOWN)),
            [2, 5, 1, 3]
        );
        check_layers(&batches, &p, &r);
        let one = allocation(&batches[0]);
        assert!(batches.iter().all(|b| allocation(b) == one));
    }

    #[test]
    fn without_d_the_projected_unknown_points_are_c_a_slice_too() {
        // As in `run`: the refinement labels every point; the projected unknown ones are C.
        let p = labels(&[1, U, 2, U, 3]); // A C A C A
        let r = labels(&[5, 6, 0, 1, 2]);
        let batches = both(&p, &r, None);
        assert_eq!(indices(batch(&batches, paths::REFINED)), [1, 3, 0, 2, 4]);
        assert_eq!(indices(batch(&batches, paths::PROJECTED)), [0, 2, 4]);
        assert_eq!(indices(batch(&batches, paths::PROJECTED_UNKNOWN)), [1, 3]);
        assert!(batch(&batches, paths::REFINED_UNKNOWN).positions.is_empty());
        check_layers(&batches, &p, &r);
        let one = allocation(&batches[0]);
        assert!(batches.iter().all(|b| allocation(b) == one));
    }

    #[test]
    fn runs_long_and_short_are_gathered_as_point_by_point() {
        // Runs of 1 to 19 points of one group (the gather copies run by run, 8 codes at a
        // time while they last), against a stable partition point by point.
        let (mut p, mut r) = (Vec::new(), Vec::new());
        for run in 0..40u32 {
            let g = run.wrapping_mul(0x9E37_79B9) >> 30;
            let len = 1 + (run * 7 % 19) as usize;
            for j in 0..len {
                let id = (j % 6) as u8;
                p.push(Label::from_id_or_unknown(if g & 1 == 1 { id } else { U }));
                r.push(Label::from_id_or_unknown(if g & 2 == 2 {
                    id + 1
                } else {
                    U
                }));
            }
        }
        let batches = both(&p, &r, None);
        let group =
            |i: usize| usize::from(!p[i].is_unknown()) | usize::from(!r[i].is_unknown()) << 1;
        let want: Vec<usize> = [C, A, B, D]
            .iter()
            .flat_map(|&g| (0..p.len()).filter(move |&i| group(i) == g))
            .collect();
        let (c, a, b) = [C, A, B]
            .map(|g| (0..p.len()).filter(|&i| group(i) == g).count())
            .into();
        assert!(
            c > 0 && a > 0 && b > 0 && want.len() > c + a + b,
            "every group"
        );
        assert_eq!(indices(batch(&batches, paths::REFINED)), want[..c + a]);
        assert_eq!(
            indices(batch(&batches, paths::PROJECTED)),
            want[c..c + a + b]
        );
        assert_eq!(
            indices(batch(&batches, paths::REFINED_UNKNOWN)),
            want[c + a..]
        );
        check_layers(&batches, &p, &r);
    }

    #[test]
    fn one_layer_alone_is_its_known_then_its_unknown_points() {
        let l = labels(&[U, 3, U, 0, 6]);
        let xyz = cloud(5);
        for refined in [false, true] {
            let clusters = vec![None; 5];
            let batches = cloud_batches(
                Layers {
                    positions_m: &xyz,
                    projected: (!refined).then_some(&l[..]),
                    refined: refined.then_some(&l[..]),
                    clusters: Some(&clusters),
                },
                color,
            );
            let (known, unknown) = if refined {
                (paths::REFINED, paths::REFINED_UNKNOWN)
            } else {
                (paths::PROJECTED, paths::PROJECTED_UNKNOWN)
            };
            assert_eq!(entities(&batches), [known, unknown, paths::CLUSTERS]);
            assert_eq!(indices(batch(&batches, paths::CLUSTERS)), [1, 3, 4, 0, 2]);
            assert_eq!(indices(batch(&batches, known)), [1, 3, 4]);
            assert_eq!(ids(batch(&batches, known)), [3, 0, 6]);
            assert_eq!(indices(batch(&batches, unknown)), [0, 2]);
            let one = allocation(&batches[2]);
            assert!(batches.iter().all(|b| allocation(b) == one), "{known}");
        }
    }

    #[test]
    fn an_empty_cloud_logs_empty_batches() {
        let batches = cloud_batches(
            Layers {
                positions_m: &[],
                projected: Some(&[]),
                refined: Some(&[]),
                clusters: Some(&[]),
            },
            color,
        );
        assert_eq!(batches.len(), 5);
        assert!(batches.iter().all(|b| b.positions.is_empty()));
        assert!(ids(batch(&batches, paths::REFINED)).is_empty());
    }

    #[test]
    fn all_unknown_points_go_to_the_unknown_entities() {
        let l = labels(&[U; 4]);
        let batches = both(&l, &l, None);
        for (known, unknown) in [
            (paths::PROJECTED, paths::PROJECTED_UNKNOWN),
            (paths::REFINED, paths::REFINED_UNKNOWN),
        ] {
            assert!(batch(&batches, known).positions.is_empty(), "{known}");
            assert!(ids(batch(&batches, known)).is_empty(), "{known}");
            assert_eq!(indices(batch(&batches, unknown)), [0, 1, 2, 3]);
        }
    }
}

#[cfg(test)]
mod timing {
    use super::*;
    use std::time::Instant;

    /// Median of 31 runs of `f`, microseconds.
    fn median_us(mut f: impl FnMut()) -> f64 {
        let mut t: Vec<f64> = (0..31)
            .map(|_| {
                let t0 = Instant::now();
                f();
                t0.elapsed().as_secs_f64() * 1e6
            })
            .collect();
        t.sort_by(f64::total_cmp);
        t[15]
    }

    /// What the gather costs against one copy of the positions and against 1a703d7's
    /// design (positions copied once, both layers' class ids mapped): a handover frame's
    /// size, one point in six unknown in projected (in runs; GATHER_NOISY=1: spread at
    /// random), none in refined.
    /// `cargo test --release --features rerun -p bodyseg-view gather_timing -- --ignored
    /// --nocapture`
    #[test]
    #[ignore = "a timing, not a check"]
    fn gather_timing() {
        let n = 350_000;
        let xyz: Vec<Vec3> = (0..n).map(|i| [i as f32, 1.0, 2.0]).collect();
        // Noisy: unknown points spread at random; coherent: in runs (60 of every 360).
        let hash = |i: usize| (i as u32).wrapping_mul(0x9E37_79B9) >> 16;
        let noisy = std::env::var_os("GATHER_NOISY").is_some();
        let p: Vec<Label> = (0..n)
            .map(|i| match (noisy, hash(i) % 6, i % 360 < 60) {
                (true, 0, _) | (false, _, true) => Label::UNKNOWN,
                (_, k, _) => Label::from_id_or_unknown(k as u8),
            })
            .collect();
        let r: Vec<Label> = (0..n)
            .map(|i| Label::from_id_or_unknown((hash(i) % 7) as u8))
            .collect();
        let copy = median_us(|| {
            std::hint::black_box(xyz.as_flattened().to_vec());
        });
        let before = median_us(|| {
            std::hint::black_box(xyz.as_flattened().to_vec());
            for l in [&p, &r] {
                std::hint::black_box(l.iter().map(|l| u16::from(l.id())).collect::<Vec<u16>>());
            }
        });
        let gather = median_us(|| {
            std::hint::black_box(cloud_batches(
                Layers {
                    positions_m: &xyz,
                    projected: Some(&p),
                    refined: Some(&r),
                    clusters: None,
                },
                |_| Rgba32(0),
            ));
        });
        println!(
            "{n} points: positions copied {copy:.0} us; 1a703d7 (copy + class ids) \
             {before:.0} us; gathered (runs per group, appended, class ids) {gather:.0} us"
        );
    }
}
