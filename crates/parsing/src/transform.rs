//! SCHP's pre- and post-processing (ALGORITHM.md §2), pure functions on buffers.
//!
//! Pre-processing maps the whole image into the square network input with the similarity
//! transform `x' = (x - cx)·k + (S-1)/2`, `y' = (y - cy)·k + (S-1)/2`, with
//! `(cx, cy) = ((w-1)/2, (h-1)/2)` and `k = (S-1)/max(w-1, h-1)`: the image keeps its
//! aspect ratio, is centred, and the short side is padded with black (the box enlarged on
//! its short side to the input's aspect ratio). Sampling is bilinear with border 0: a
//! neighbour outside the image contributes 0 (OpenCV's `warpAffine` with
//! `BORDER_CONSTANT`), and each sample is rounded to a whole grey level (SCHP warps the
//! 8-bit image into an 8-bit image), before normalisation.
//!
//! Post-processing upsamples the logits to S×S (bilinear, PyTorch's `interpolate` with the
//! sidecar's `align_corners`), warps them back to the image with the inverse transform
//! (bilinear, border 0), and takes softmax and argmax per pixel.

use crate::spec::{ChannelOrder, ModelSpec};
use bodyseg_core::{NUM_CLASSES, RgbImage};

/// The similarity transform between an image of `width` × `height` pixels and the square
/// network input of side `input_size` (pixel centres at integer coordinates in both).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InputTransform {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Input side S, pixels.
    pub input_size: u32,
    /// Scale k = (S-1)/max(w-1, h-1), input pixels per image pixel.
    pub scale: f64,
    /// Image centre ((w-1)/2, (h-1)/2), image pixels.
    pub center_px: [f64; 2],
}

impl InputTransform {
    /// The transform for an image of `width` × `height` (each ≥ 1) and input side
    /// `input_size` (≥ 2). A 1-pixel-wide-and-high image maps to the input centre with
    /// k = S-1 (max(w-1, h-1) is taken as at least 1).
    pub fn new(width: u32, height: u32, input_size: u32) -> InputTransform {
        let longest = f64::from(width.max(height).saturating_sub(1).max(1));
        InputTransform {
            width,
            height,
            input_size,
            scale: f64::from(input_size.saturating_sub(1)) / longest,
            center_px: [
                f64::from(width.saturating_sub(1)) / 2.0,
                f64::from(height.saturating_sub(1)) / 2.0,
            ],
        }
    }

    /// (S-1)/2: the input's centre, input pixels.
    fn input_center(&self) -> f64 {
        f64::from(self.input_size.saturating_sub(1)) / 2.0
    }

    /// The 2×3 matrix `input_from_image`: `[x', y'] = M · [x, y, 1]`.
    pub fn input_from_image(&self) -> [[f64; 3]; 2] {
        let (k, c) = (self.scale, self.input_center());
        [
            [k, 0.0, c - k * self.center_px[0]],
            [0.0, k, c - k * self.center_px[1]],
        ]
    }

    /// The 2×3 matrix `image_from_input`, the inverse of [`Self::input_from_image`].
    pub fn image_from_input(&self) -> [[f64; 3]; 2] {
        let (k, c) = (self.scale, self.input_center());
        [
            [1.0 / k, 0.0, self.center_px[0] - c / k],
            [0.0, 1.0 / k, self.center_px[1] - c / k],
        ]
    }

    /// Image pixel → input pixel.
    pub fn to_input(&self, x: f64, y: f64) -> [f64; 2] {
        let (k, c) = (self.scale, self.input_center());
        [
            (x - self.center_px[0]) * k + c,
            (y - self.center_px[1]) * k + c,
        ]
    }

    /// Input pixel → image pixel.
    pub fn to_image(&self, x: f64, y: f64) -> [f64; 2] {
        let (k, c) = (self.scale, self.input_center());
        [
            (x - c) / k + self.center_px[0],
            (y - c) / k + self.center_px[1],
        ]
    }
}

/// Bilinear neighbours of coordinate `x` on an axis of `n` samples: `(i0, w0, i1, w1)`
/// with the weight of a neighbour outside `0..n` set to 0 (border 0).
#[inline]
fn taps(x: f64, n: usize) -> (usize, f32, usize, f32) {
    let x0 = x.floor();
    let f = (x - x0) as f32;
    let i0 = x0 as i64;
    let inside = |i: i64| i >= 0 && (i as usize) < n;
    let (w0, w1) = (
        if inside(i0) { 1.0 - f } else { 0.0 },
        if inside(i0 + 1) { f } else { 0.0 },
    );
    let clamp = |i: i64| i.clamp(0, n as i64 - 1) as usize;
    (clamp(i0), w0, clamp(i0 + 1), w1)
}

/// `v` in `0.0..=255.0` rounded to the nearest whole number, ties to even (what
/// `f32::round_ties_even` gives): adding and subtracting 1.5·2²³ leaves no fraction bits in
/// f32, and IEEE addition rounds ties to even. `round_ties_even` itself is a libm call on
/// baseline x86-64 (no SSE4.1): the pre-processing of a 960×540 view took 8.3-9.2 ms with
/// it, 2.9-4.8 ms with this and 3.8-5.4 ms unrounded (`cargo bench -p bodyseg-parsing
/// --bench inference -- preprocess`, runs interleaved on a loaded machine).
#[inline]
fn whole_grey_level(v: f32) -> f32 {
    const MAGIC: f32 = 12_582_912.0;
    (v + MAGIC) - MAGIC
}

/// Warps `image` into the S×S input with bilinear sampling, border 0, each sample rounded
/// to a whole grey level (ties to even) as SCHP's `cv2.warpAffine` into a uint8 image
/// gives: the RGB values in `0..=255`, row-major, 3 per pixel (HWC, RGB order), not
/// normalised.
pub fn warp_to_input(image: &RgbImage, t: &InputTransform) -> Vec<f32> {
    let s = t.input_size as usize;
    let (w, h) = (image.width as usize, image.height as usize);
    let mut out = vec![0.0f32; s * s * 3];
    if w == 0 || h == 0 {
        return out;
    }
    let xs: Vec<_> = (0..s)
        .map(|x| taps(t.to_image(x as f64, 0.0)[0], w))
        .collect();
    for y in 0..s {
        let (r0, wy0, r1, wy1) = taps(t.to_image(0.0, y as f64)[1], h);
        if wy0 == 0.0 && wy1 == 0.0 {
            continue;
        }
        let row = &mut out[y * s * 3..(y + 1) * s * 3];
        for (x, &(c0, wx0, c1, wx1)) in xs.iter().enumerate() {
            if wx0 == 0.0 && wx1 == 0.0 {
                continue;
            }
            let px = |r: usize, c: usize| 3 * (r * w + c);
            let (a, b, c, d) = (px(r0, c0), px(r0, c1), px(r1, c0), px(r1, c1));
            let (wa, wb, wc, wd) = (wy0 * wx0, wy0 * wx1, wy1 * wx0, wy1 * wx1);
            for ch in 0..3 {
                let v = |i: usize| f32::from(image.rgb[i + ch]);
                row[3 * x + ch] = whole_grey_level(wa * v(a) + wb * v(b) + wc * v(c) + wd * v(d));
            }
        }
    }
    out
}

/// Normalises warped RGB samples (HWC, `[0, 255]`) into the network's planar input
/// (CHW, `spec.channel_order`): `(value / 255 - mean) / std` per channel. Appends the
/// 3·S·S values to `out` (one view of a batch).
pub fn normalize_to_chw(samples_rgb: &[f32], spec: &ModelSpec, out: &mut Vec<f32>) {
    let n = samples_rgb.len() / 3;
    for plane in 0..3 {
        // Source RGB channel of this input plane.
        let src = match spec.channel_order {
            ChannelOrder::Rgb => plane,
            ChannelOrder::Bgr => 2 - plane,
        };
        let (mean, inv_std) = (spec.mean[plane], 1.0 / spec.std[plane]);
        out.extend((0..n).map(|i| (samples_rgb[3 * i + src] / 255.0 - mean) * inv_std));
    }
}

/// Source coordinate and neighbour weights of output sample `i` when resizing an axis of
/// `n_in` samples to `n_out` (PyTorch's bilinear `interpolate`): align_corners maps the
/// end samples onto each other; otherwise half-pixel centres, negative sources clamped to 0.
fn resize_taps(n_in: usize, n_out: usize, align_corners: bool) -> Vec<(usize, usize, f32)> {
    (0..n_out)
        .map(|i| {
            let src = if align_corners {
                if n_out > 1 {
                    i as f64 * (n_in as f64 - 1.0) / (n_out as f64 - 1.0)
                } else {
                    0.0
                }
            } else {
                ((i as f64 + 0.5) * n_in as f64 / n_out as f64 - 0.5).max(0.0)
            };
            let i0 = (src.floor() as usize).min(n_in - 1);
            let i1 = (i0 + 1).min(n_in - 1);
            (i0, i1, (src - i0 as f64) as f32)
        })
        .collect()
}

/// Upsamples planar logits `[7, h, w]` to `[s, s]`, bilinear, and returns them
/// interleaved (HWC: the 7 logits of a pixel side by side).
pub fn upsample_logits(
    logits: &[f32],
    h: usize,
    w: usize,
    s: usize,
    align_corners: bool,
) -> Vec<f32> {
    let ys = resize_taps(h, s, align_corners);
    let xs = resize_taps(w, s, align_corners);
    let mut out = vec![0.0f32; s * s * NUM_CLASSES];
    for (y, &(r0, r1, fy)) in ys.iter().enumerate() {
        for (x, &(c0, c1, fx)) in xs.iter().enumerate() {
            let o = (y * s + x) * NUM_CLASSES;
            for ch in 0..NUM_CLASSES {
                let p = &logits[ch * h * w..(ch + 1) * h * w];
                let top = p[r0 * w + c0] * (1.0 - fx) + p[r0 * w + c1] * fx;
                let bottom = p[r1 * w + c0] * (1.0 - fx) + p[r1 * w + c1] * fx;
                out[o + ch] = top * (1.0 - fy) + bottom * fy;
            }
        }
    }
    out
}

/// The per-pixel result of post-processing one view at the image's size.
#[derive(Clone, Debug, PartialEq)]
pub struct PixelClasses {
    /// Winning class id per pixel, row-major.
    pub class_ids: Vec<u8>,
    /// Softmax probability of the winning class per pixel.
    pub probs: Vec<f32>,
    /// All 7 softmax probabilities, planar `[7][height * width]`, when asked for.
    pub class_probs: Option<Vec<f32>>,
}

/// Warps S×S interleaved logits (from [`upsample_logits`]) back to the image with the
/// inverse of `t` (bilinear, border 0), then softmax and argmax per pixel (ties go to the
/// lower class id).
pub fn warp_back_and_classify(
    logits_hwc: &[f32],
    t: &InputTransform,
    keep_class_probs: bool,
) -> PixelClasses {
    let s = t.input_size as usize;
    let (w, h) = (t.width as usize, t.height as usize);
    let n = w * h;
    let mut class_ids = vec![0u8; n];
    let mut probs = vec![0.0f32; n];
    let mut class_probs = keep_class_probs.then(|| vec![0.0f32; NUM_CLASSES * n]);
    let xs: Vec<_> = (0..w)
        .map(|u| taps(t.to_input(u as f64, 0.0)[0], s))
        .collect();
    for v in 0..h {
        let (r0, wy0, r1, wy1) = taps(t.to_input(0.0, v as f64)[1], s);
        for (u, &(c0, wx0, c1, wx1)) in xs.iter().enumerate() {
            let at = |r: usize, c: usize| &logits_hwc[(r * s + c) * NUM_CLASSES..][..NUM_CLASSES];
            let (a, b, c, d) = (at(r0, c0), at(r0, c1), at(r1, c0), at(r1, c1));
            let (wa, wb, wc, wd) = (wy0 * wx0, wy0 * wx1, wy1 * wx0, wy1 * wx1);
            let mut z = [0.0f32; NUM_CLASSES];
            for ch in 0..NUM_CLASSES {
                z[ch] = wa * a[ch] + wb * b[ch] + wc * c[ch] + wd * d[ch];
            }
            let (best, max) =
                z.iter()
                    .enumerate()
                    .fold((0, f32::NEG_INFINITY), |(bi, bv), (i, &v)| {
                        if v > bv { (i, v) } else { (bi, bv) }
                    });
            let mut sum = 0.0f32;
            for zc in &mut z {
                *zc = (*zc - max).exp();
                sum += *zc;
            }
            let i = v * w + u;
            class_ids[i] = best as u8;
            probs[i] = (z[best] / sum).clamp(0.0, 1.0);
            if let Some(all) = class_probs.as_mut() {
                for ch in 0..NUM_CLASSES {
                    all[ch * n + i] = (z[ch] / sum).clamp(0.0, 1.0);
                }
            }
        }
    }
    PixelClasses {
        class_ids,
        probs,
        class_probs,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transform_maps_the_image_box_into_the_input_square() {
        // 640x480, S = 512: k = 511/639; corners of the long side land on 0 and 511, the
        // short side is centred.
        let t = InputTransform::new(640, 480, 512);
        let [x, y] = t.to_input(0.0, 0.0);
        assert!((x - 0.0).abs() < 1e-12, "{x}");
        let [x2, y2] = t.to_input(639.0, 479.0);
        assert!((x2 - 511.0).abs() < 1e-12, "{x2}");
        assert!(
            (y + y2 - 511.0).abs() < 1e-9,
            "short side centred: {y} {y2}"
        );
        let [u, v] = t.to_image(x2, y2);
        assert!((u - 639.0).abs() < 1e-9 && (v - 479.0).abs() < 1e-9);
        let m = t.input_from_image();
        let inv = t.image_from_input();
        let (px, py) = (123.25, 77.5);
        let q = [m[0][0] * px + m[0][2], m[1][1] * py + m[1][2]];
        let back = [inv[0][0] * q[0] + inv[0][2], inv[1][1] * q[1] + inv[1][2]];
        assert!((back[0] - px).abs() < 1e-9 && (back[1] - py).abs() < 1e-9);
    }

    #[test]
    fn taps_give_border_zero() {
        assert_eq!(taps(-1.5, 4).1 + taps(-1.5, 4).3, 0.0);
        let (i0, w0, i1, w1) = taps(-0.25, 4);
        assert_eq!((i0, i1), (0, 0));
        assert_eq!((w0, w1), (0.0, 0.75));
        let (_, w0, _, w1) = taps(3.5, 4);
        assert_eq!((w0, w1), (0.5, 0.0));
    }

    #[test]
    fn whole_grey_level_is_round_ties_even() {
        for i in 0..=255 * 64 {
            let v = i as f32 / 64.0;
            assert_eq!(whole_grey_level(v), v.round_ties_even(), "{v}");
        }
        for v in [0.5f32, 1.5, 2.5, 254.5, 0.49999997, 0.50000006, 255.0, 0.0] {
            assert_eq!(whole_grey_level(v), v.round_ties_even(), "{v}");
        }
    }

    #[test]
    fn warped_samples_are_whole_grey_levels_rounded_to_even() {
        // A 2x2 image into S = 3: k = 2, input x' = 1 samples the image half-way between
        // its columns (and rows). Columns (0, 1) blend to 0.5 -> 0, (0, 3) to 1.5 -> 2,
        // (0, 255) to 127.5 -> 128, as cv2.warpAffine into a uint8 image rounds them.
        let t = InputTransform::new(2, 2, 3);
        for (right, want) in [(1u8, 0.0f32), (3, 2.0), (255, 128.0)] {
            let image =
                RgbImage::new(2, 2, [0, 0, 0, right, right, right].repeat(2)).expect("2x2 RGB");
            let warped = warp_to_input(&image, &t);
            // Input pixel (1, 0): image row 0, half-way between its columns.
            assert_eq!(&warped[3..6], &[want; 3], "right column {right}");
            assert_eq!(&warped[6..9], &[f32::from(right); 3]);
            assert!(warped.iter().all(|v| v.fract() == 0.0), "{warped:?}");
        }
    }

    #[test]
    fn upsample_matches_pytorch_on_a_ramp() {
        // A 2-sample ramp [0, 1] upsampled to 4: align_corners=True gives 0, 1/3, 2/3, 1;
        // False gives 0, 0.25, 0.75, 1 (torch.nn.functional.interpolate).
        let mut logits = vec![0.0f32; NUM_CLASSES * 2];
        logits[1] = 1.0; // class 0, (row 0, col 1)
        for (align, want) in [
            (true, [0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0]),
            (false, [0.0, 0.25, 0.75, 1.0]),
        ] {
            let up = upsample_logits(&logits, 1, 2, 4, align);
            for (x, w) in want.iter().enumerate() {
                // Row 0 of class 0; every row equals row 0 (a single source row).
                let got = up[x * NUM_CLASSES];
                assert!((got - w).abs() < 1e-6, "align {align} x {x}: {got} vs {w}");
            }
        }
    }

    #[test]
    fn constant_logits_come_back_as_their_argmax_everywhere() {
        let t = InputTransform::new(40, 30, 16);
        let mut logits = vec![0.0f32; NUM_CLASSES * 4 * 4];
        for i in 0..16 {
            logits[3 * 16 + i] = 5.0; // class 3 wins
        }
        let up = upsample_logits(&logits, 4, 4, 16, true);
        let out = warp_back_and_classify(&up, &t, true);
        assert!(out.class_ids.iter().all(|&c| c == 3));
        let p = 5f32.exp() / (5f32.exp() + 6.0);
        assert!(out.probs.iter().all(|&q| (q - p).abs() < 1e-5));
        let all = out.class_probs.expect("asked for");
        let n = 40 * 30;
        for i in [0, 17, n - 1] {
            let s: f32 = (0..NUM_CLASSES).map(|c| all[c * n + i]).sum();
            assert!((s - 1.0).abs() < 1e-5);
        }
    }
}
