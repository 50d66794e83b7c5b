//! Image points, the rotated region of interest around a person and the crop that feeds the
//! landmark model.

use super::model::INPUT;
use crate::segmenter::PixelBox;
use bodyseg_core::RgbImage;

pub(crate) type P2 = [f64; 2];

pub(crate) fn sub(a: P2, b: P2) -> P2 {
    [a[0] - b[0], a[1] - b[1]]
}
pub(crate) fn add(a: P2, b: P2) -> P2 {
    [a[0] + b[0], a[1] + b[1]]
}
pub(crate) fn scale(a: P2, k: f64) -> P2 {
    [a[0] * k, a[1] * k]
}
pub(crate) fn dot(a: P2, b: P2) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
pub(crate) fn norm(a: P2) -> f64 {
    a[0].hypot(a[1])
}
pub(crate) fn mid(a: P2, b: P2) -> P2 {
    [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0]
}

/// A square, rotated region of interest in the image (MediaPipe's `NormalizedRect` in
/// pixels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Roi {
    /// Centre, image px (pixel centres at integers).
    pub centre_px: P2,
    /// Side, image px.
    pub side_px: f64,
    /// Rotation, radians; 0 = upright (see the module's conventions).
    pub angle_rad: f64,
}

impl Roi {
    /// The upright ROI around a box: its centre, side `scale` × the box's longer side.
    pub fn from_box(b: &PixelBox, scale: f64) -> Roi {
        let w = b.x1 - b.x0 + 1.0;
        let h = b.y1 - b.y0 + 1.0;
        Roi {
            centre_px: [(b.x0 + b.x1) / 2.0, (b.y0 + b.y1) / 2.0],
            side_px: w.max(h) * scale,
            angle_rad: 0.0,
        }
    }

    /// MediaPipe's ROI from alignment points (AlignmentPointsRects + RectTransformation
    /// with `square_long`): centre = `centre`, side = 2 |scale_pt − centre| × `scale`,
    /// rotated so that centre → scale_pt points up in the ROI.
    pub fn from_alignment(centre: P2, scale_pt: P2, scale: f64) -> Roi {
        let v = sub(scale_pt, centre);
        Roi {
            centre_px: centre,
            side_px: 2.0 * norm(v) * scale,
            angle_rad: v[0].atan2(-v[1]),
        }
    }

    /// (right, down) unit axes in image pixels.
    pub fn axes(&self) -> (P2, P2) {
        let (s, c) = self.angle_rad.sin_cos();
        ([c, s], [-s, c])
    }

    /// Tensor coordinates (0..256, pixel edges) → image px.
    pub fn tensor_to_image(&self, t: P2) -> P2 {
        let (right, down) = self.axes();
        let ox = (t[0] / INPUT as f64 - 0.5) * self.side_px;
        let oy = (t[1] / INPUT as f64 - 0.5) * self.side_px;
        add(self.centre_px, add(scale(right, ox), scale(down, oy)))
    }

    /// Image px → tensor coordinates (the inverse of [`Roi::tensor_to_image`]).
    pub fn image_to_tensor(&self, p: P2) -> P2 {
        let (right, down) = self.axes();
        let d = sub(p, self.centre_px);
        [
            (dot(d, right) / self.side_px + 0.5) * INPUT as f64,
            (dot(d, down) / self.side_px + 0.5) * INPUT as f64,
        ]
    }
}

/// The ROI cropped into a `size`×`size` RGB tensor, NHWC, values in [0, 1]: tensor pixel
/// (i, j) samples the image at the ROI point of tensor coordinates ((i + 0.5)·256/size,
/// (j + 0.5)·256/size), bilinear, coordinates clamped to the image (MediaPipe's
/// BORDER_REPLICATE). An empty image gives zeros.
pub fn crop(image: &RgbImage, roi: &Roi, size: usize) -> Vec<f32> {
    let mut out = Vec::new();
    crop_into(image, roi, size, &mut out);
    out
}

/// [`crop`] into `out` (its allocation reused).
pub fn crop_into(image: &RgbImage, roi: &Roi, size: usize, out: &mut Vec<f32>) {
    out.clear();
    out.resize(size * size * 3, 0.0);
    let (w, h) = (image.width as usize, image.height as usize);
    if w == 0 || h == 0 || image.rgb.len() < w * h * 3 {
        return;
    }
    let step = INPUT as f64 / size as f64;
    // tensor_to_image, with the axes computed once: p = origin + tx·ex + ty·ey.
    let (right, down) = roi.axes();
    let k = roi.side_px / INPUT as f64;
    let ex = scale(right, k);
    let ey = scale(down, k);
    let origin = sub(
        roi.centre_px,
        add(
            scale(right, roi.side_px / 2.0),
            scale(down, roi.side_px / 2.0),
        ),
    );
    let (wmax, hmax) = ((w - 1) as f64, (h - 1) as f64);
    // Each column's offset along `ex`, computed once instead of once per row.
    let along: Vec<P2> = (0..size)
        .map(|i| scale(ex, (i as f64 + 0.5) * step))
        .collect();
    let rgb = &image.rgb[..w * h * 3];
    for (j, out_row) in out.chunks_exact_mut(size * 3).enumerate() {
        let ty = (j as f64 + 0.5) * step;
        let row = add(origin, scale(ey, ty));
        for (px, &off) in out_row.chunks_exact_mut(3).zip(&along) {
            let p = add(row, off);
            let x = p[0].clamp(0.0, wmax);
            let y = p[1].clamp(0.0, hmax);
            // Clamped to [0, w-1] (or NaN, which casts to 0 as floor's NaN does): the cast
            // is the floor without a libm call, and cannot leave the image.
            let x0 = x as usize;
            let y0 = y as usize;
            let x1 = (x0 + 1).min(w - 1);
            let y1 = (y0 + 1).min(h - 1);
            let fx = x - x0 as f64;
            let fy = y - y0 as f64;
            let at = |k: usize| -> [f64; 3] {
                let p = &rgb[k * 3..k * 3 + 3];
                [f64::from(p[0]), f64::from(p[1]), f64::from(p[2])]
            };
            let (a, b, c, d) = (
                at(y0 * w + x0),
                at(y0 * w + x1),
                at(y1 * w + x0),
                at(y1 * w + x1),
            );
            for ch in 0..3 {
                let top = a[ch] * (1.0 - fx) + b[ch] * fx;
                let bot = c[ch] * (1.0 - fx) + d[ch] * fx;
                px[ch] = ((top * (1.0 - fy) + bot * fy) / 255.0) as f32;
            }
        }
    }
}

/// Sets the pixels of a crop `out` (made by [`crop_into`] of `roi` at `size`) whose centre
/// falls outside `keep` (image px) to `value` in every channel.
pub fn blank_outside(out: &mut [f32], roi: &Roi, size: usize, keep: &PixelBox, value: f32) {
    let step = INPUT as f64 / size as f64;
    for j in 0..size {
        for i in 0..size {
            let p = roi.tensor_to_image([(i as f64 + 0.5) * step, (j as f64 + 0.5) * step]);
            let inside = (keep.x0..=keep.x1).contains(&p[0]) && (keep.y0..=keep.y1).contains(&p[1]);
            if !inside {
                let k = (j * size + i) * 3;
                if let Some(px) = out.get_mut(k..k + 3) {
                    px.fill(value);
                }
            }
        }
    }
}
