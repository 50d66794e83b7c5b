//! The person mask of the BlazePose + BodyPix fusion cleaned ([`BlazePoseOptions`]'s
//! `bodypix_background_below` and `drop_detached`; docs/notes/2026-12-03-blazepose.md,
//! 2026-12-04 session 42): most pixels the fusion loses on the real photographs are extra
//! ones (person where the ground truth has background), of two kinds, each with its rule.
//!
//! - A rim around the body: BlazePose's mask, low-resolution and cut at 0.35, is a few
//!   pixels too wide. Where BodyPix, which covers the pixel and sees the person, is nearly
//!   sure of background ([`veto_blazepose`]), the pixel is not the person's.
//! - Islands: BodyPix sees body parts in things near a person (a horse's body under its
//!   rider). A connected piece of the fused mask that holds no pixel of BlazePose's person,
//!   no confident landmark and lies in no region where BlazePose found nobody is nobody's
//!   ([`drop_detached`]). Anchored by landmarks and BlazePose's mask, not by area: a person
//!   cut in two by a thin object in front keeps both halves as long as each holds part of
//!   BlazePose's mask or a landmark.
//!
//! [`BlazePoseOptions`]: super::BlazePoseOptions

use crate::blazepose::PersonLabels;
use crate::bodypix::PartMap;
use bodyseg_core::{Label, LabelImage};

/// The probability given to a pixel [`drop_detached`] turns to background: BodyPix said
/// person, the rule says nobody's; neither is sure.
pub const DETACHED_BACKGROUND_PROB: f32 = 0.5;

/// A landmark anchors a piece of the mask ([`drop_detached`]) when its visibility is at
/// least this (the model's "not occluded" probability: an occluded point may sit on the
/// occluder) and its presence at least the rule's `min_presence`.
pub const ANCHOR_MIN_VISIBILITY: f64 = 0.5;

/// Whether `label` is a body class (1–6).
fn is_body(label: Label) -> bool {
    (1..7).contains(&label.id())
}

/// A person's pixels are checked against BodyPix ([`veto_blazepose`]) only when BodyPix
/// sees at least this fraction of them as person (probability ≥ its threshold): where
/// BodyPix misses a person as a whole (a dark figure in shadow behind a car), its
/// "background" says nothing about the outline. On the real photographs' tune and test
/// images (pixels in the person boxes) BodyPix sees 55–97 % of each person it finds at its
/// 0.7, 1 % and 11 % of the two it misses; 0.5 (half) splits them.
pub const MIN_SEEN_BY_BODYPIX: f64 = 0.5;

/// The pixels of BlazePose's `person` where BodyPix's merged map (`map`, the whole image)
/// covers the pixel and its person probability is below `below` are not the person's
/// (class 0, probability 1 − BodyPix's person probability), when BodyPix sees the person
/// ([`MIN_SEEN_BY_BODYPIX`] of its pixels at probability ≥ `threshold`). BodyPix's 16-pixel
/// grid sees the body's outline more sharply than BlazePose's mask (256 cells over a ROI
/// twice the person's size, cut at the rule's 0.35). `below` ≤ 0 or a map that is not the
/// whole image: no change.
pub fn veto_blazepose(
    person: &mut PersonLabels,
    map: &PartMap,
    below: f64,
    threshold: f64,
    width: usize,
) {
    if below <= 0.0 || map.u0 != 0 || map.v0 != 0 || map.u1 != width {
        return;
    }
    let (below, threshold) = (below as f32, threshold as f32);
    let (pw, u1) = (person.u1 - person.u0, person.u1.min(width));
    if u1 <= person.u0 {
        return;
    }
    // One pass over the window, row slices side by side: the person's pixels (class ≠ 0),
    // those BodyPix sees, and the few below `below` (indices in the window).
    let (mut body, mut seen) = (0usize, 0usize);
    let mut vetoed: Vec<(usize, f32)> = Vec::new();
    for v in person.v0..person.v1.min(map.v1) {
        let start = (v - person.v0) * pw;
        let classes = &person.class[start..start + (u1 - person.u0)];
        let bodypix = &map.person[v * width + person.u0..v * width + u1];
        for (i, (&class, &p)) in classes.iter().zip(bodypix).enumerate() {
            let is_person = class != 0;
            body += usize::from(is_person);
            seen += usize::from(is_person && p >= threshold);
            if is_person && (0.0..below).contains(&p) {
                vetoed.push((start + i, p));
            }
        }
    }
    if body == 0 || (seen as f64) < MIN_SEEN_BY_BODYPIX * body as f64 {
        return;
    }
    for (k, p) in vetoed {
        person.class[k] = 0;
        person.score[k] = f32::INFINITY;
        person.prob[k] = 1.0 - p;
    }
}

/// Where a piece of the person mask is anchored ([`drop_detached`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Anchors {
    /// Per image pixel, row-major: BlazePose's person is there.
    pub blazepose: Vec<bool>,
    /// Confident landmarks, image px (rounded to the nearest pixel).
    pub landmarks: Vec<[f64; 2]>,
    /// Windows `(u0, u1, v0, v1)` (end-exclusive) of regions where BlazePose found nobody:
    /// BodyPix's person there has no landmark to hold on to, so any piece reaching into one
    /// is kept.
    pub free_windows: Vec<(usize, usize, usize, usize)>,
}

/// A run of body pixels on one row: columns `start..end`.
#[derive(Clone, Copy, Debug)]
struct Run {
    start: usize,
    end: usize,
}

/// Union-find root of run `i`, with path halving.
fn root(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// The pieces (8-connected) of the body pixels of `labels` that are anchored — hold a
/// pixel of `anchors.blazepose` or a landmark, or reach into a free window — stay; the
/// others become background with probability [`DETACHED_BACKGROUND_PROB`]. Anchors of
/// another size than the image: no change. Runs of pixels per row joined by union-find:
/// one pass over the labels and a few operations per run.
pub fn drop_detached(labels: &mut LabelImage, anchors: &Anchors) {
    let (w, h) = (labels.width as usize, labels.height as usize);
    let n = labels.labels.len();
    if n != w * h || anchors.blazepose.len() != n {
        return;
    }
    // Runs, row by row (`first[v]..first[v + 1]` are row v's).
    let mut runs: Vec<Run> = Vec::new();
    let mut first = Vec::with_capacity(h + 1);
    for row in labels.labels.chunks_exact(w.max(1)) {
        first.push(runs.len());
        let mut u = 0;
        while u < w {
            if !is_body(row[u]) {
                u += 1;
                continue;
            }
            let start = u;
            while u < w && is_body(row[u]) {
                u += 1;
            }
            runs.push(Run { start, end: u });
        }
    }
    first.push(runs.len());
    if runs.is_empty() {
        return;
    }
    let mut parent: Vec<usize> = (0..runs.len()).collect();
    for v in 1..h {
        let (above, here) = (first[v - 1]..first[v], first[v]..first[v + 1]);
        let mut a = above.start;
        for b in here {
            // Runs above that touch run b, diagonals included: a.start ≤ b.end and
            // b.start ≤ a.end (ends exclusive).
            while a < above.end && runs[a].end < runs[b].start {
                a += 1;
            }
            let mut k = a;
            while k < above.end && runs[k].start <= runs[b].end {
                let (ra, rb) = (root(&mut parent, k), root(&mut parent, b));
                if ra != rb {
                    parent[ra.max(rb)] = ra.min(rb);
                }
                k += 1;
            }
        }
    }
    let mut kept = vec![false; runs.len()];
    for v in 0..h {
        for r in first[v]..first[v + 1] {
            let Run { start, end } = runs[r];
            let row = &anchors.blazepose[v * w..(v + 1) * w];
            let held = row[start..end].iter().any(|&b| b)
                || anchors
                    .free_windows
                    .iter()
                    .any(|&(u0, u1, v0, v1)| (v0..v1).contains(&v) && start < u1 && u0 < end);
            if held {
                let k = root(&mut parent, r);
                kept[k] = true;
            }
        }
    }
    for &[x, y] in &anchors.landmarks {
        let (u, v) = (x.round(), y.round());
        if !(u >= 0.0 && v >= 0.0 && u < w as f64 && v < h as f64) {
            continue;
        }
        let (u, v) = (u as usize, v as usize);
        if let Some(r) = (first[v]..first[v + 1]).find(|&r| runs[r].start <= u && u < runs[r].end) {
            let k = root(&mut parent, r);
            kept[k] = true;
        }
    }
    let probs = labels.probs.get_or_insert_with(|| vec![1.0; n]);
    for v in 0..h {
        for r in first[v]..first[v + 1] {
            if kept[root(&mut parent, r)] {
                continue;
            }
            let Run { start, end } = runs[r];
            labels.labels[v * w + start..v * w + end].fill(Label::BACKGROUND);
            probs[v * w + start..v * w + end].fill(DETACHED_BACKGROUND_PROB);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A label image from rows of characters: '.' background, a digit its class.
    fn image_of(rows: &[&str]) -> LabelImage {
        let (w, h) = (rows[0].len(), rows.len());
        let labels = rows
            .iter()
            .flat_map(|r| r.bytes())
            .map(|b| match b {
                b'.' => Label::BACKGROUND,
                d => Label::from_id_or_unknown(d - b'0'),
            })
            .collect();
        LabelImage {
            width: w as u32,
            height: h as u32,
            labels,
            probs: Some(vec![0.9; w * h]),
        }
    }

    fn ids(labels: &LabelImage) -> Vec<String> {
        labels
            .labels
            .chunks(labels.width as usize)
            .map(|r| {
                r.iter()
                    .map(|l| match l.id() {
                        0 => '.',
                        d => char::from(b'0' + d),
                    })
                    .collect()
            })
            .collect()
    }

    /// Anchors: BlazePose's person where `rows` has an 'x'.
    fn blazepose_at(rows: &[&str]) -> Vec<bool> {
        rows.iter()
            .flat_map(|r| r.bytes())
            .map(|b| b == b'x')
            .collect()
    }

    /// The rider and the horse: the body held by BlazePose's mask stays, a detached blob
    /// goes, a blob touching the body only diagonally stays (8-connected), a blob holding a
    /// confident landmark stays, a blob reaching into a free window stays.
    #[test]
    fn pieces_without_an_anchor_are_dropped() {
        let mut labels = image_of(&[
            "11........",
            "22...3....",
            "22....44..",
            "..5.......",
            "......2...",
            "6.....22..",
        ]);
        let bare = Anchors {
            blazepose: blazepose_at(&[
                "x.........",
                "..........",
                "..........",
                "..........",
                "..........",
                "..........",
            ]),
            ..Anchors::default()
        };
        let mut only_body = labels.clone();
        drop_detached(&mut only_body, &bare);
        assert_eq!(
            ids(&only_body),
            [
                "11........",
                "22........",
                "22........",
                "..5.......",
                "..........",
                "..........",
            ]
        );
        let probs = only_body.probs.as_ref().expect("probabilities");
        assert_eq!(probs[10 + 5], DETACHED_BACKGROUND_PROB);
        assert_eq!(probs[0], 0.9);
        let anchors = Anchors {
            landmarks: vec![[6.6, 1.8], [f64::NAN, 0.0], [-3.0, 5.0]],
            free_windows: vec![(0, 2, 5, 6)],
            ..bare
        };
        drop_detached(&mut labels, &anchors);
        assert_eq!(
            ids(&labels),
            [
                "11........",
                "22...3....",
                "22....44..",
                "..5.......",
                "..........",
                "6.........",
            ]
        );
    }

    /// A person behind a thin pole: both halves hold part of BlazePose's mask and stay.
    #[test]
    fn a_person_cut_by_a_thin_occluder_keeps_both_halves() {
        let mut labels = image_of(&["22.22", "22.22", "55.55"]);
        let anchors = Anchors {
            blazepose: blazepose_at(&["x...x", ".....", "....."]),
            ..Anchors::default()
        };
        let before = labels.clone();
        drop_detached(&mut labels, &anchors);
        assert_eq!(labels, before);
    }

    /// A one-row person of BlazePose with these classes from column 0 (probability 0.9).
    fn person_of(classes: &[u8]) -> PersonLabels {
        let n = classes.len();
        PersonLabels {
            u0: 0,
            u1: n,
            v0: 0,
            v1: 1,
            class: classes.to_vec(),
            prob: vec![0.9; n],
            score: classes
                .iter()
                .map(|&c| if c == 0 { f32::INFINITY } else { 0.1 })
                .collect(),
            depth_m: None,
        }
    }

    fn map_of(person: Vec<f32>) -> PartMap {
        let n = person.len();
        PartMap {
            u0: 0,
            u1: n,
            v0: 0,
            v1: 1,
            person,
            class: vec![0; n],
            class_prob: vec![0.0; n],
        }
    }

    /// Below 0.15 and covered: not the person's (legs too); not covered (−1), above 0.15 or
    /// not the person's: unchanged. A person BodyPix does not see is left whole.
    #[test]
    fn bodypix_background_is_believed_on_people_bodypix_sees() {
        // 4 of the 8 body pixels at ≥ 0.7: seen.
        let map = map_of(vec![0.1, 0.2, 0.05, -1.0, 0.1, 0.9, 0.8, 0.9, 0.95]);
        let mut person = person_of(&[1, 2, 5, 6, 0, 2, 3, 4, 4]);
        let before = person.clone();
        veto_blazepose(&mut person, &map, 0.0, 0.7, 9);
        assert_eq!(person, before, "off");
        veto_blazepose(&mut person, &map_of(vec![0.1; 8]), 0.15, 0.7, 8);
        assert_eq!(person, before, "a map of another size");
        veto_blazepose(&mut person, &map, 0.15, 0.7, 9);
        assert_eq!(person.class, [0, 2, 0, 6, 0, 2, 3, 4, 4]);
        assert!(!person.score[0].is_finite() && !person.score[2].is_finite());
        assert!((person.prob[0] - 0.9).abs() < 1e-6 && (person.prob[2] - 0.95).abs() < 1e-6);
        assert_eq!(&person.prob[3..], &before.prob[3..]);
        // 2 of 8 seen: BodyPix missed this person; nothing changes.
        let unseen = map_of(vec![0.1, 0.2, 0.05, -1.0, 0.1, 0.9, 0.8, 0.1, 0.1]);
        let mut person = before.clone();
        veto_blazepose(&mut person, &unseen, 0.15, 0.7, 9);
        assert_eq!(person, before, "not seen");
    }

    /// xorshift64*: a small seeded generator for the property test.
    fn next(state: &mut u64) -> u64 {
        *state ^= *state >> 12;
        *state ^= *state << 25;
        *state ^= *state >> 27;
        state.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// The same as [`drop_detached`], by flood fill from every anchor (8 neighbours).
    fn naive(labels: &LabelImage, anchors: &Anchors) -> Vec<u8> {
        let (w, h) = (labels.width as usize, labels.height as usize);
        let body: Vec<bool> = labels.labels.iter().map(|&l| is_body(l)).collect();
        let mut seeds: Vec<usize> = (0..w * h)
            .filter(|&i| body[i] && anchors.blazepose[i])
            .collect();
        for &(u0, u1, v0, v1) in &anchors.free_windows {
            for v in v0..v1.min(h) {
                seeds.extend((u0..u1.min(w)).map(|u| v * w + u).filter(|&i| body[i]));
            }
        }
        for &[x, y] in &anchors.landmarks {
            let (x, y) = (x.round(), y.round());
            let (u, v) = (x as usize, y as usize);
            if x >= 0.0 && y >= 0.0 && u < w && v < h && body[v * w + u] {
                seeds.push(v * w + u);
            }
        }
        let mut kept = vec![false; w * h];
        while let Some(i) = seeds.pop() {
            if kept[i] {
                continue;
            }
            kept[i] = true;
            let (u, v) = ((i % w) as i64, (i / w) as i64);
            for dv in -1..=1 {
                for du in -1..=1 {
                    let (x, y) = (u + du, v + dv);
                    if x >= 0 && y >= 0 && x < w as i64 && y < h as i64 {
                        let j = y as usize * w + x as usize;
                        if body[j] && !kept[j] {
                            seeds.push(j);
                        }
                    }
                }
            }
        }
        (0..w * h)
            .map(|i| if kept[i] { labels.labels[i].id() } else { 0 })
            .collect()
    }

    /// Random masks (sparse to dense), anchors, landmarks and windows: the run-based
    /// labelling keeps exactly the pixels a flood fill from the anchors reaches.
    /// `BODYSEG_TEST_SEED` overrides the seed.
    #[test]
    fn drop_detached_matches_a_flood_fill() {
        let seed = std::env::var("BODYSEG_TEST_SEED")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(0x29f_u64);
        let mut state = seed | 1;
        for case in 0..300 {
            let (w, h) = (
                1 + next(&mut state) as usize % 23,
                1 + next(&mut state) as usize % 17,
            );
            let density = next(&mut state) % 100;
            let labels: Vec<Label> = (0..w * h)
                .map(|_| {
                    let body = next(&mut state) % 100 < density;
                    Label::from_id_or_unknown(if body {
                        1 + (next(&mut state) % 6) as u8
                    } else {
                        0
                    })
                })
                .collect();
            let image = LabelImage {
                width: w as u32,
                height: h as u32,
                labels,
                probs: None,
            };
            let anchors = Anchors {
                blazepose: (0..w * h).map(|_| next(&mut state) % 100 < 3).collect(),
                landmarks: (0..next(&mut state) % 4)
                    .map(|_| {
                        [
                            (next(&mut state) % 30) as f64 - 2.0,
                            (next(&mut state) % 20) as f64,
                        ]
                    })
                    .collect(),
                free_windows: (0..next(&mut state) % 2)
                    .map(|_| {
                        let (u0, v0) =
                            (next(&mut state) as usize % w, next(&mut state) as usize % h);
                        (u0, u0 + 3, v0, v0 + 2)
                    })
                    .collect(),
            };
            let want = naive(&image, &anchors);
            let mut got = image.clone();
            drop_detached(&mut got, &anchors);
            let got: Vec<u8> = got.labels.iter().map(|l| l.id()).collect();
            assert_eq!(got, want, "seed {seed}, case {case}, {w}x{h}");
        }
    }
}
