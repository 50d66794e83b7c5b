//! The preview of a frame: per camera one row of colour | depth | truth | prediction.

use crate::frame::SynthFrame;
use bodyseg_calib::Rig;
use bodyseg_core::{Class, RgbImage};

/// Height of one camera's row in the preview, pixels (half the depth image).
pub const PREVIEW_ROW_HEIGHT: u32 = 212;
const GAP: u32 = 4;

/// The colour of a label in previews: the class palette, brightened so that the dark
/// Pascal colours stay readable; background shows the dimmed camera image.
fn label_rgb(label: u8, under: [u8; 3]) -> [u8; 3] {
    match Class::from_id(label) {
        Some(Class::Background) | None => under.map(|c| c / 3),
        Some(class) => class
            .color()
            .map(|c| if c == 0 { 40 } else { c.saturating_add(70) }),
    }
}

/// Depth as a colour ramp: near = warm, far = cool, no measurement = black.
fn depth_rgb(mm: u16) -> [u8; 3] {
    if mm == 0 {
        return [0, 0, 0];
    }
    let t = ((f32::from(mm) - 500.0) / 4000.0).clamp(0.0, 1.0);
    let r = (255.0 * (1.0 - t)) as u8;
    let g = (255.0 * (1.0 - (2.0 * t - 1.0).abs())) as u8;
    let b = (255.0 * t) as u8;
    [r, g, b]
}

/// The preview of `frame` rendered with `rig` (for the image sizes): one row per
/// camera, panels colour | depth | 2D truth | prediction, scaled to
/// [`PREVIEW_ROW_HEIGHT`] pixels high.
pub fn preview(frame: &SynthFrame, rig: &Rig) -> RgbImage {
    let h = PREVIEW_ROW_HEIGHT;
    let Some(first) = rig.cameras.first() else {
        return RgbImage::filled(1, 1, [0, 0, 0]);
    };
    let color_w =
        (u64::from(first.color.width) * u64::from(h) / u64::from(first.color.height).max(1)) as u32;
    let depth_w =
        (u64::from(first.depth.width) * u64::from(h) / u64::from(first.depth.height).max(1)) as u32;
    let width = color_w * 3 + depth_w + GAP * 3;
    let n = frame.cameras.len().min(rig.cameras.len()) as u32;
    let height = n * h + n.saturating_sub(1) * GAP;
    let mut out = RgbImage::filled(width, height.max(1), [255, 255, 255]);
    for (c, (images, camera)) in frame.cameras.iter().zip(&rig.cameras).enumerate() {
        let y0 = c as u32 * (h + GAP);
        let (cw, ch) = (camera.color.width, camera.color.height);
        let (dw, dh) = (camera.depth.width, camera.depth.height);
        let x_truth = color_w + depth_w + 2 * GAP;
        let x_pred = x_truth + color_w + GAP;
        for y in 0..h {
            // Colour and label panels: box-average colour, nearest label.
            let sy0 = y * ch / h;
            let sy1 = ((y + 1) * ch / h).max(sy0 + 1).min(ch);
            for x in 0..color_w.min(width) {
                let sx0 = x * cw / color_w;
                let sx1 = ((x + 1) * cw / color_w).max(sx0 + 1).min(cw);
                let mut acc = [0u32; 3];
                let mut count = 0u32;
                for sy in sy0..sy1 {
                    for sx in sx0..sx1 {
                        let i = (sy * cw + sx) as usize * 3;
                        for k in 0..3 {
                            acc[k] += u32::from(images.color.get(i + k).copied().unwrap_or(0));
                        }
                        count += 1;
                    }
                }
                let rgb = acc.map(|a| (a / count.max(1)) as u8);
                out.set_pixel(x, y0 + y, rgb);
                let centre = (((sy0 + sy1) / 2) * cw + (sx0 + sx1) / 2) as usize;
                let truth = images.labels.get(centre).copied().unwrap_or(0);
                let pred = images.parsing.get(centre).copied().unwrap_or(0);
                out.set_pixel(x_truth + x, y0 + y, label_rgb(truth, rgb));
                out.set_pixel(x_pred + x, y0 + y, label_rgb(pred, rgb));
            }
            let sy = (y * dh / h).min(dh - 1);
            for x in 0..depth_w {
                let sx = (x * dw / depth_w).min(dw - 1);
                let mm = images
                    .depth_mm
                    .get((sy * dw + sx) as usize)
                    .copied()
                    .unwrap_or(0);
                out.set_pixel(color_w + GAP + x, y0 + y, depth_rgb(mm));
            }
        }
    }
    out
}
