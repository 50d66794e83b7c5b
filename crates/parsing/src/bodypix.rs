//! [`BodyPix`]: BodyPix 2.0 (MobileNetV1 0.75, stride 16: Google Coral's uint8 graph in
//! ONNX, `models/bodypix_mobilenet_v1_075_quant.onnx`) on person regions: per pixel a person
//! probability, a body part (24 parts → the 7 classes) and that class's probability.
//! [`crate::BlazePoseSegmenter`] takes its body parts from it (`parts`, [`fuse`]; fusion C of
//! docs/notes/2026-12-04-bodypix-probe.md).
//!
//! Crop, sizes and sampling follow `scripts/bodypix_probe.py` (the reference a test compares
//! against): the person box widened by [`BodyPixOptions::margin`] × its size on each side,
//! cut out bilinearly (Pillow's `Image.transform(EXTENT, BILINEAR)`: black where a sample
//! falls outside the image) to 16 k × 16 k' px, the longer side
//! [`BodyPixOptions::long_side`]; the graph pads one pixel (16 k + 1), so output cell i sits
//! on crop pixel 16 i; outputs are sampled back bilinearly (clamped at the grid's edges) at
//! every image pixel the widened box covers.

use crate::ParsingError;
use crate::onnx::{inference_error, load_session, named_output, run_one_input};
use crate::segmenter::PixelBox;
use bodyseg_core::{Label, LabelImage, RgbImage};
use ort::session::Session;
use ort::value::{TensorElementType, ValueType};
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// The graph's input (uint8 RGB, NHWC, height and width multiples of [`STRIDE`]).
const INPUT_NAME: &str = "sub_2";
/// Person logit output (1 channel) and its uint8 quantisation (scale, zero point).
const SEGMENTS: (&str, usize, f32, f32) = ("float_segments", 1, 0.090_011_78, 162.0);
/// Part logit output (24 channels, body-pix's `PART_CHANNELS` order) and its quantisation.
const PARTS: (&str, usize, f32, f32) = ("float_part_heatmaps", NUM_PARTS, 0.081_925_73, 72.0);
/// Body parts of BodyPix.
pub const NUM_PARTS: usize = 24;
/// Output stride: output cell i ↔ input pixel 16 i.
pub const STRIDE: usize = 16;
/// BodyPix's 24 parts (`PART_CHANNELS`: left/right face, upper arms front/back, lower arms,
/// hands, torso front/back, upper legs, lower legs, feet) → class id: faces → head, torso
/// → torso, upper arms, lower arms + hands, upper legs, lower legs + feet.
pub const PART_TO_CLASS: [u8; NUM_PARTS] = [
    1, 1, 3, 3, 3, 3, 4, 4, 4, 4, 4, 4, 2, 2, 5, 5, 5, 5, 6, 6, 6, 6, 6, 6,
];
/// Below this person probability a pixel's part is not sampled (class 0): such a pixel is
/// BodyPix's background, and where BlazePose gives a person there its label stays
/// ([`fuse`]). Most of a region's window is far below it; sampling the 24 part logits is
/// most of BodyPix's time after the model.
pub const PART_FLOOR: f32 = 0.01;
/// The largest crop side taken, px ([`BodyPixOptions::long_side`] is clamped to it).
pub const MAX_LONG_SIDE: usize = 2048;

/// How BodyPix runs on a region; defaults are the probe's (chosen on the tune split), but
/// for the crop side.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyPixOptions {
    /// The region is widened by this × its width (height) on each side. Default 0.3.
    pub margin: f64,
    /// The crop's longer side, px (rounded to a multiple of 16). Default 384, for the 80 ms
    /// budget of a two-person view: on the real photographs mIoU 0.550 (tune split 0.542)
    /// against 0.561 (0.550) at 448 and 0.558 (0.549) at the probe's 512, with ~35 % less
    /// BodyPix time than 512.
    pub long_side: usize,
    /// A pixel is BodyPix's person where its person probability is at least this. Default 0.7.
    pub threshold: f64,
}

impl Default for BodyPixOptions {
    fn default() -> Self {
        BodyPixOptions {
            margin: 0.3,
            long_side: 384,
            threshold: 0.7,
        }
    }
}

/// BodyPix's reading of a window of the image (one region, or the merge of a view's).
#[derive(Clone, Debug, PartialEq)]
pub struct PartMap {
    /// Window: columns `u0..u1`, rows `v0..v1` of the image.
    pub u0: usize,
    /// End column (exclusive).
    pub u1: usize,
    /// First row.
    pub v0: usize,
    /// End row (exclusive).
    pub v1: usize,
    /// Person probability per window pixel, row-major; −1 where no crop covers it.
    pub person: Vec<f32>,
    /// Class id (1–6) of the part with the largest logit (0 where not covered or the person
    /// probability is below [`PART_FLOOR`]).
    pub class: Vec<u8>,
    /// That class's probability given a person (softmax over the 24 parts, summed over the
    /// class's parts, sampled bilinearly from the output grid).
    pub class_prob: Vec<f32>,
}

impl PartMap {
    /// A window with no pixel covered.
    fn empty(u0: usize, u1: usize, v0: usize, v1: usize) -> PartMap {
        let n = (u1 - u0) * (v1 - v0);
        PartMap {
            u0,
            u1,
            v0,
            v1,
            person: vec![-1.0; n],
            class: vec![0; n],
            class_prob: vec![0.0; n],
        }
    }
}

/// One ONNX Runtime session of a BodyPix graph, with its crop buffer.
pub struct BodyPix {
    session: Session,
    model_path: PathBuf,
    /// The crop, reused from run to run (NHWC uint8).
    input: Vec<u8>,
}

impl std::fmt::Debug for BodyPix {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BodyPix")
            .field("model_path", &self.model_path)
            .finish_non_exhaustive()
    }
}

/// The dims of a uint8 tensor type, `None` for anything else.
fn uint8_dims(dtype: &ValueType) -> Option<Vec<i64>> {
    match dtype {
        ValueType::Tensor { ty, shape, .. } if *ty == TensorElementType::Uint8 => {
            Some(shape.to_vec())
        }
        _ => None,
    }
}

/// Crop side for a widened extent of `n` px scaled to the longer side (body-pix's sizing,
/// as the reference: `16 × max(1, round_half_even((n − 1) / 16))`).
fn snap(n: f64) -> usize {
    let k = ((n - 1.0) / STRIDE as f64).round_ties_even().max(1.0);
    if k.is_finite() {
        (k as usize).min(MAX_LONG_SIDE / STRIDE) * STRIDE
    } else {
        STRIDE
    }
}

/// The region `bounds` (inclusive pixel centres) widened by `margin` × its size on each
/// side, as pixel edges `[x0, y0, x1, y1]`.
fn widened_rect(bounds: &PixelBox, margin: f64) -> [f64; 4] {
    let (w, h) = (bounds.x1 - bounds.x0 + 1.0, bounds.y1 - bounds.y0 + 1.0);
    [
        bounds.x0 - margin * w,
        bounds.y0 - margin * h,
        bounds.x1 + 1.0 + margin * w,
        bounds.y1 + 1.0 + margin * h,
    ]
}

/// `rect` (pixel edges) of `image` resampled to `win`×`hin` into `out` (RGB, row-major), as
/// Pillow's `transform(EXTENT, BILINEAR)`: the sample of crop pixel (i, j) is image point
/// (x0 + (i + ½) w / win, y0 + (j + ½) h / hin) in pixel edges; black when it is outside
/// the image, else bilinear between pixel centres with indices clamped, the value truncated.
pub(crate) fn crop_extent(
    image: &RgbImage,
    rect: [f64; 4],
    (win, hin): (usize, usize),
    out: &mut Vec<u8>,
) {
    let (w_img, h_img) = (image.width as usize, image.height as usize);
    out.clear();
    out.resize(win * hin * 3, 0);
    if w_img == 0 || h_img == 0 {
        return;
    }
    let [x0, y0, x1, y1] = rect;
    let px = |x: usize, y: usize, c: usize| f64::from(image.rgb[(y * w_img + x) * 3 + c]);
    let columns: Vec<_> = (0..win)
        .map(|i| pillow_tap((x1 - x0) / win as f64 * (i as f64 + 0.5) + x0, w_img))
        .collect();
    for j in 0..hin {
        let Some((ya, yb, dy)) = pillow_tap((y1 - y0) / hin as f64 * (j as f64 + 0.5) + y0, h_img)
        else {
            continue;
        };
        // Pillow replicates the last row downwards but not the last column's neighbour.
        let yb = usize::try_from(yb).ok().filter(|&y| y < h_img);
        for (i, column) in columns.iter().enumerate() {
            let Some((xa, xb, dx)) = *column else {
                continue;
            };
            let xb = xb.clamp(0, w_img as i64 - 1) as usize;
            for c in 0..3 {
                let lerp = |y: usize| px(xa, y, c) + (px(xb, y, c) - px(xa, y, c)) * dx;
                let v1 = lerp(ya);
                let v2 = yb.map_or(v1, lerp);
                let v = v1 + (v2 - v1) * dy;
                out[(j * win + i) * 3 + c] = v.clamp(0.0, 255.0) as u8;
            }
        }
    }
}

/// Pillow's bilinear tap at `pos` (pixel edges) on an axis of `n` pixels: `None` outside
/// `[0, n)`, else (the pixel before, clamped; the raw index after; the weight of the after).
fn pillow_tap(pos: f64, n: usize) -> Option<(usize, i64, f64)> {
    if !(0.0..n as f64).contains(&pos) {
        return None;
    }
    let f = pos - 0.5;
    let i = f.floor();
    Some((
        (i as i64).clamp(0, n as i64 - 1) as usize,
        i as i64 + 1,
        f - i,
    ))
}

/// Bilinear position on a grid of `n` cells: (cell, next cell, weight of the next).
fn grid_pos(c: f64, n: usize) -> (usize, usize, f32) {
    let c = c.clamp(0.0, (n - 1) as f64);
    let i = (c.floor() as usize).min(n - 1);
    (i, (i + 1).min(n - 1), (c - i as f64) as f32)
}

impl BodyPix {
    /// Loads a BodyPix graph from its bytes (`model_path` names it in errors) with
    /// `threads` intra-op threads and checks its shape: input `sub_2` uint8 `[1,h,w,3]`,
    /// outputs `float_segments` uint8 `[1,h',w',1]` and `float_part_heatmaps` uint8
    /// `[1,h',w',24]`.
    ///
    /// # Errors
    /// [`ParsingError::RuntimeLibrary`], [`ParsingError::ModelLoad`],
    /// [`ParsingError::NotBodyPix`] naming the file and what differs.
    pub fn new(
        runtime_library: &Path,
        model_bytes: &[u8],
        model_path: &Path,
        threads: usize,
    ) -> Result<BodyPix, ParsingError> {
        let session = load_session(runtime_library, model_bytes, model_path, threads, false)?;
        let not = |reason: String| ParsingError::NotBodyPix {
            reason,
            path: model_path.to_path_buf(),
        };
        let inputs = session.inputs();
        let fits = |d: &[i64], channels: usize| {
            d.len() == 4 && (d[0] == 1 || d[0] == -1) && d[3] == channels as i64
        };
        let input_ok = inputs.len() == 1
            && inputs[0].name() == INPUT_NAME
            && uint8_dims(inputs[0].dtype()).is_some_and(|d| fits(&d, 3));
        if !input_ok {
            let got: Vec<String> = inputs
                .iter()
                .map(|i| format!("{} {:?}", i.name(), i.dtype()))
                .collect();
            return Err(not(format!(
                "inputs [{}], expected one: {INPUT_NAME} uint8 [1, h, w, 3]",
                got.join(", ")
            )));
        }
        for (name, channels, _, _) in [SEGMENTS, PARTS] {
            let Some(out) = session.outputs().iter().find(|o| o.name() == name) else {
                return Err(not(format!("no output {name}")));
            };
            let dims = uint8_dims(out.dtype());
            if !dims.as_ref().is_some_and(|d| fits(d, channels)) {
                return Err(not(format!(
                    "output {name} is {:?}, expected uint8 [1, h, w, {channels}]",
                    out.dtype()
                )));
            }
        }
        Ok(BodyPix {
            session,
            model_path: model_path.to_path_buf(),
            input: Vec::new(),
        })
    }

    /// BodyPix on the region `bounds` (inclusive pixel centres) of `image`: the window of
    /// the widened box inside the image, `None` when the region is unusable (not finite,
    /// empty) or misses the image.
    ///
    /// # Errors
    /// [`ParsingError::Inference`] naming the model file.
    pub fn run_region(
        &mut self,
        image: &RgbImage,
        bounds: &PixelBox,
        options: &BodyPixOptions,
    ) -> Result<Option<PartMap>, ParsingError> {
        let b = bounds;
        let usable = [b.x0, b.y0, b.x1, b.y1, options.margin]
            .iter()
            .all(|v| v.is_finite())
            && b.x1 >= b.x0
            && b.y1 >= b.y0
            && options.margin >= 0.0;
        if !usable {
            return Ok(None);
        }
        let rect = widened_rect(bounds, options.margin);
        let [x0, y0, x1, y1] = rect;
        let (w_img, h_img) = (image.width as usize, image.height as usize);
        let u0 = x0.floor().max(0.0) as usize;
        let v0 = y0.floor().max(0.0) as usize;
        let u1 = (x1.ceil().max(0.0) as usize).min(w_img);
        let v1 = (y1.ceil().max(0.0) as usize).min(h_img);
        if u1 <= u0 || v1 <= v0 {
            return Ok(None);
        }
        let (w, h) = (x1 - x0, y1 - y0);
        let k = (options.long_side.clamp(STRIDE, MAX_LONG_SIDE) + 1) as f64 / w.max(h);
        let (win, hin) = (snap(w * k), snap(h * k));
        crop_extent(image, rect, (win, hin), &mut self.input);
        let path = &self.model_path;
        let infer = |cause: String| inference_error(path, cause);
        let outputs = run_one_input(
            &mut self.session,
            INPUT_NAME,
            [1, hin, win, 3],
            &self.input,
            path,
        )?;
        let (gw, gh) = (win / STRIDE + 1, hin / STRIDE + 1);
        let get = |(name, channels, scale, zero): (&str, usize, f32, f32)| {
            let (shape, data) = named_output::<u8>(&outputs, name, path)?;
            let want = [1, gh as i64, gw as i64, channels as i64];
            if shape[..] != want[..] || data.len() != gw * gh * channels {
                return Err(infer(format!(
                    "{name} is {shape:?}, expected {want:?} for a {win}×{hin} input"
                )));
            }
            Ok(data
                .iter()
                .map(|&q| (f32::from(q) - zero) * scale)
                .collect::<Vec<f32>>())
        };
        let segments = get(SEGMENTS)?;
        let parts = get(PARTS)?;
        drop(outputs);
        let grid = Grid {
            gw,
            segments: &segments,
            parts: &parts,
            class_probs: class_probs(&parts),
        };
        let mut map = PartMap::empty(u0, u1, v0, v1);
        let ww = u1 - u0;
        // Image pixel centre → crop pixel (Pillow's EXTENT) → output cell (align corners).
        let to_cell_x = |u: usize| ((u as f64 + 0.5 - x0) * win as f64 / w - 0.5) / STRIDE as f64;
        let to_cell_y = |v: usize| ((v as f64 + 0.5 - y0) * hin as f64 / h - 0.5) / STRIDE as f64;
        let columns: Vec<(usize, usize, f32)> =
            (u0..u1).map(|u| grid_pos(to_cell_x(u), gw)).collect();
        map.person
            .par_chunks_mut(ww)
            .zip(map.class.par_chunks_mut(ww))
            .zip(map.class_prob.par_chunks_mut(ww))
            .enumerate()
            .for_each(|(r, ((person, class), prob))| {
                let row = grid_pos(to_cell_y(v0 + r), gh);
                grid.sample_row(row, &columns, person, class, prob);
            });
        Ok(Some(map))
    }
}

/// Per output cell, the probability of each class given a person: the softmax of the 24
/// part logits summed over each class's parts (`[cell][class]`, class 0 unused).
fn class_probs(parts: &[f32]) -> Vec<[f32; 7]> {
    parts
        .chunks_exact(NUM_PARTS)
        .map(|logits| {
            let max = logits.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            let mut per_class = [0.0f32; 7];
            let mut sum = 0.0;
            for (p, &l) in logits.iter().enumerate() {
                let e = (l - max).exp();
                per_class[usize::from(PART_TO_CLASS[p])] += e;
                sum += e;
            }
            per_class.map(|e| e / sum)
        })
        .collect()
}

/// One run's dequantised outputs on its `gw`×`gh` grid.
struct Grid<'a> {
    gw: usize,
    segments: &'a [f32],
    parts: &'a [f32],
    class_probs: Vec<[f32; 7]>,
}

impl Grid<'_> {
    /// Samples one image row (grid rows `ya`, `yb`, weight `fy`) at `columns` (each a
    /// bilinear position on the grid's columns) into the row's outputs.
    fn sample_row(
        &self,
        (ya, yb, fy): (usize, usize, f32),
        columns: &[(usize, usize, f32)],
        person: &mut [f32],
        class: &mut [u8],
        prob: &mut [f32],
    ) {
        // The two grid rows blended first: 25 values per grid column.
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let blend = |data: &[f32], channels: usize| -> Vec<f32> {
            let (ra, rb) = (
                &data[ya * self.gw * channels..][..self.gw * channels],
                &data[yb * self.gw * channels..][..self.gw * channels],
            );
            ra.iter().zip(rb).map(|(&a, &b)| lerp(a, b, fy)).collect()
        };
        let seg = blend(self.segments, 1);
        let parts = blend(self.parts, NUM_PARTS);
        for (k, &(xa, xb, fx)) in columns.iter().enumerate() {
            let logit = lerp(seg[xa], seg[xb], fx);
            person[k] = 1.0 / (1.0 + (-logit).exp());
            if person[k] < PART_FLOOR {
                continue; // class 0, probability 0: not sampled
            }
            let (pa, pb) = (
                &parts[xa * NUM_PARTS..][..NUM_PARTS],
                &parts[xb * NUM_PARTS..][..NUM_PARTS],
            );
            let (mut best, mut best_v) = (0usize, f32::NEG_INFINITY);
            for p in 0..NUM_PARTS {
                let v = lerp(pa[p], pb[p], fx);
                if v > best_v {
                    best_v = v;
                    best = p;
                }
            }
            let c = PART_TO_CLASS[best];
            class[k] = c;
            let cp = |y: usize, x: usize| self.class_probs[y * self.gw + x][usize::from(c)];
            let top = lerp(cp(ya, xa), cp(ya, xb), fx);
            let bottom = lerp(cp(yb, xa), cp(yb, xb), fx);
            prob[k] = lerp(top, bottom, fy);
        }
    }
}

/// The regions of a view merged over a `width`×`height` image: where windows overlap, the
/// region with the higher person probability wins (ties: the earlier region).
pub fn merge_part_maps(width: usize, height: usize, maps: &[PartMap]) -> PartMap {
    let mut all = PartMap::empty(0, width, 0, height);
    for m in maps {
        let mw = m.u1 - m.u0;
        for v in m.v0..m.v1.min(height) {
            for u in m.u0..m.u1.min(width) {
                let (k, i) = ((v - m.v0) * mw + (u - m.u0), v * width + u);
                if m.person[k] > all.person[i] {
                    all.person[i] = m.person[k];
                    all.class[i] = m.class[k];
                    all.class_prob[i] = m.class_prob[k];
                }
            }
        }
    }
    all
}

/// BodyPix's labels alone over a merged map (`merge_part_maps` of the whole image): its
/// class where the person probability is at least `threshold`, else background; for tests
/// and studies.
pub fn part_labels(map: &PartMap, threshold: f64) -> Vec<u8> {
    map.person
        .iter()
        .zip(&map.class)
        .map(|(&p, &c)| if f64::from(p) >= threshold { c } else { 0 })
        .collect()
}

/// BlazePose's labels (`labels`, with probabilities) and BodyPix's merged map of the same
/// image fused (fusion C of the probe note): a pixel is a person's where either says so
/// (BlazePose: a body class; BodyPix: person probability ≥ `threshold`); there the class is
/// BodyPix's, except where BlazePose gives an upper or lower leg (its legs are the better:
/// BodyPix's lower legs score 0.02–0.09 on the tune photographs), no BodyPix crop covers
/// the pixel or BodyPix's person probability is below [`PART_FLOOR`] (no part sampled),
/// where BlazePose's label stays. Probabilities: BodyPix's class probability ×
/// the larger of the two person probabilities (BlazePose's is its label's) where BodyPix
/// decides, BlazePose's where it decides; background pixels 1 − the larger person
/// probability. A `map` of another size leaves `labels` as they are.
pub fn fuse(labels: &mut LabelImage, map: &PartMap, threshold: f64) {
    let width = labels.width as usize;
    let n = labels.labels.len();
    if width == 0 || map.person.len() != n || (map.u0, map.u1, map.v0) != (0, width, 0) {
        return;
    }
    let probs = labels.probs.get_or_insert_with(|| vec![1.0; n]);
    let threshold = threshold as f32;
    // Rows in parallel: each pixel's result depends on that pixel alone.
    labels
        .labels
        .par_chunks_mut(width)
        .zip(probs.par_chunks_mut(width))
        .enumerate()
        .for_each(|(v, (labels, probs))| {
            let row = v * width..(v + 1) * width;
            let parts = map.person[row.clone()]
                .iter()
                .zip(&map.class[row.clone()])
                .zip(&map.class_prob[row]);
            for ((label, prob), ((&person, &class), &class_prob)) in
                labels.iter_mut().zip(probs.iter_mut()).zip(parts)
            {
                fuse_pixel(label, prob, (person, class, class_prob), threshold);
            }
        });
}

/// One pixel of [`fuse`]: BlazePose's `label` and `prob` with BodyPix's merged (person
/// probability, class, class probability) there.
fn fuse_pixel(
    label: &mut Label,
    prob: &mut f32,
    (person, class, class_prob): (f32, u8, f32),
    threshold: f32,
) {
    let id = label.id();
    let blazepose_person = (1..7).contains(&id);
    if id == 5 || id == 6 {
        return;
    }
    if person < 0.0 || (blazepose_person && class == 0) {
        return; // no BodyPix crop here, or no part sampled (below PART_FLOOR)
    }
    if !(blazepose_person || person >= threshold) {
        *label = Label::BACKGROUND;
        *prob = prob.min(1.0 - person);
        return;
    }
    let sure = if blazepose_person {
        person.max(*prob)
    } else {
        person
    };
    *label = Label::from_id_or_unknown(class);
    *prob = (class_prob * sure).clamp(0.0, 1.0);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_round_like_the_reference() {
        // The reference's int(round((n - 1) / 16)) * 16, halves to even.
        assert_eq!(snap(513.0), 512);
        assert_eq!(snap(25.0), 16 * 2); // (24 / 16 = 1.5) -> 2
        assert_eq!(snap(41.0), 16 * 2); // 2.5 -> 2
        assert_eq!(snap(3.0), 16);
        assert_eq!(snap(f64::NAN), 16);
        assert_eq!(snap(1e12), MAX_LONG_SIDE);
    }

    #[test]
    fn the_crop_is_black_outside_and_exact_on_a_one_to_one_grid() {
        let (w, h) = (5usize, 4usize);
        let rgb: Vec<u8> = (0..w * h * 3).map(|i| (i * 7 % 256) as u8).collect();
        let image = RgbImage::new(w as u32, h as u32, rgb.clone()).expect("w*h*3 bytes");
        let mut out = Vec::new();
        // One crop pixel per image pixel, shifted by 2 px left and up: the first two columns
        // and rows are outside (black), the rest the image's pixels.
        crop_extent(&image, [-2.0, -2.0, 5.0, 4.0], (7, 6), &mut out);
        for j in 0..6 {
            for i in 0..7 {
                for c in 0..3 {
                    let want = if i < 2 || j < 2 {
                        0
                    } else {
                        rgb[((j - 2) * w + i - 2) * 3 + c]
                    };
                    assert_eq!(out[(j * 7 + i) * 3 + c], want, "({i}, {j}) {c}");
                }
            }
        }
    }

    #[test]
    fn class_probabilities_sum_the_parts_of_each_class() {
        let mut logits = vec![0.0f32; NUM_PARTS];
        logits[0] = 10.0; // left face
        logits[1] = 10.0; // right face
        let p = class_probs(&logits)[0];
        assert!(p[1] > 0.99, "{p:?}");
        assert!((p.iter().sum::<f32>() - 1.0).abs() < 1e-5);
    }

    /// A one-row window from column `u0` with these values (class probability 0.5).
    fn map_of(u0: usize, person: Vec<f32>, class: Vec<u8>) -> PartMap {
        let n = person.len();
        PartMap {
            u0,
            u1: u0 + n,
            v0: 0,
            v1: 1,
            person,
            class,
            class_prob: vec![0.5; n],
        }
    }

    /// Pixel by pixel: BlazePose's legs stay; a BlazePose person takes BodyPix's part even
    /// where BodyPix's probability is low; BodyPix alone adds a person; neither = background;
    /// an uncovered pixel or one with no part sampled keeps BlazePose's label; a map of
    /// another size changes nothing.
    #[test]
    fn fusion_takes_bodypix_parts_inside_the_union_and_keeps_blazepose_legs() {
        let ids = [5u8, 2, 0, 0, 3, 2];
        let mut labels = LabelImage {
            width: 6,
            height: 1,
            labels: ids.iter().map(|&i| Label::from_id_or_unknown(i)).collect(),
            probs: Some(vec![0.9, 0.8, 0.7, 0.9, 0.6, 0.7]),
        };
        let map = map_of(
            0,
            vec![0.9, 0.1, 0.8, 0.2, -1.0, 0.005],
            vec![2, 1, 4, 3, 0, 0],
        );
        let before = labels.clone();
        fuse(&mut labels, &map_of(0, vec![0.9], vec![1]), 0.7);
        assert_eq!(labels, before);
        fuse(&mut labels, &map, 0.7);
        let got: Vec<u8> = labels.labels.iter().map(|l| l.id()).collect();
        assert_eq!(got, [5, 1, 4, 0, 3, 2]);
        let p = labels.probs.expect("probabilities");
        assert!((p[1] - 0.5 * 0.8).abs() < 1e-6, "{p:?}");
        assert!((p[2] - 0.5 * 0.8).abs() < 1e-6, "{p:?}");
        assert!((p[3] - 0.8).abs() < 1e-6, "{p:?}");
        assert_eq!((p[0], p[4], p[5]), (0.9, 0.6, 0.7));
    }

    #[test]
    fn overlapping_regions_go_to_the_likelier_person() {
        let a = map_of(0, vec![0.9, 0.2], vec![1, 2]);
        let b = map_of(1, vec![0.8, 0.3], vec![4, 6]);
        let m = merge_part_maps(4, 1, &[a, b]);
        assert_eq!(m.class, [1, 4, 6, 0]);
        assert_eq!(m.person, [0.9, 0.8, 0.3, -1.0]);
        assert_eq!(part_labels(&m, 0.7), [1, 4, 0, 0]);
    }

    /// [`fuse`] (rows in parallel) equals fusing the merged map pixel by pixel: random windows
    /// (overlapping, reaching past the image's right and bottom edges), random labels.
    #[test]
    fn fusing_rows_in_parallel_equals_fusing_pixel_by_pixel() {
        let (w, h) = (37usize, 23usize);
        // A fixed linear congruential sequence: the same case every run.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = |n: usize| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((state >> 33) % n as u64) as usize
        };
        for case in 0..20 {
            let maps: Vec<PartMap> = (0..3)
                .map(|_| {
                    let (u0, v0) = (next(w), next(h));
                    let (u1, v1) = (u0 + 1 + next(w), v0 + 1 + next(h));
                    let n = (u1 - u0) * (v1 - v0);
                    let mut m = PartMap::empty(u0, u1, v0, v1);
                    for k in 0..n {
                        // Coarse values: ties between regions are common (the earlier wins).
                        m.person[k] = next(20) as f32 / 19.0;
                        m.class[k] = if m.person[k] < PART_FLOOR {
                            0
                        } else {
                            next(7) as u8
                        };
                        m.class_prob[k] = next(1000) as f32 / 999.0;
                    }
                    m
                })
                .collect();
            let labels = LabelImage {
                width: w as u32,
                height: h as u32,
                labels: (0..w * h)
                    .map(|_| Label::from_id_or_unknown(next(8) as u8))
                    .collect(),
                probs: Some((0..w * h).map(|_| next(1000) as f32 / 999.0).collect()),
            };
            let merged = merge_part_maps(w, h, &maps);
            // The serial reference: every pixel of the merged map in turn.
            let mut want = labels.clone();
            let probs = want.probs.as_mut().expect("probabilities");
            for (i, (label, prob)) in want.labels.iter_mut().zip(probs.iter_mut()).enumerate() {
                let part = (merged.person[i], merged.class[i], merged.class_prob[i]);
                fuse_pixel(label, prob, part, 0.7);
            }
            let mut got = labels.clone();
            fuse(&mut got, &merged, 0.7);
            assert_eq!(got, want, "case {case}");
            assert_ne!(got, labels, "case {case}: the maps change something");
        }
    }
}
