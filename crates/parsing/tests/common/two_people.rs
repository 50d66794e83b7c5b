//! The two-person view of the `blazepose_view` bench and the BlazePose segmenter's tests
//! (included with `#[path]`: one copy for both).

use bodyseg_core::RgbImage;
use bodyseg_parsing::{PersonRegion, PixelBox};
use bodyseg_synth::{Synth, preset};

/// Camera 0 of frame 0 of `robot_cell`, seed 1 (960 wide), and the regions of its two
/// largest people.
pub fn view() -> (RgbImage, Vec<PersonRegion>) {
    let config = preset("robot_cell").expect("preset");
    let frame = Synth::new(config, 1).expect("synth").frame(0);
    let cam = &frame.cameras[0];
    let w = 960usize;
    let h = cam.color.len() / 3 / w;
    let image = RgbImage::new(w as u32, h as u32, cam.color.clone()).expect("960 wide RGB");
    // Bounding box and pixel count per person id (0 = nobody).
    let mut boxes: Vec<(usize, [usize; 4])> = vec![(0, [usize::MAX, usize::MAX, 0, 0]); 256];
    for (k, &id) in cam.color_person.iter().enumerate() {
        if id == 0 {
            continue;
        }
        let (u, v) = (k % w, k / w);
        let b = &mut boxes[usize::from(id)];
        b.0 += 1;
        b.1 = [b.1[0].min(u), b.1[1].min(v), b.1[2].max(u), b.1[3].max(v)];
    }
    boxes.sort_by_key(|b| std::cmp::Reverse(b.0));
    let regions = boxes
        .iter()
        .take(2)
        .filter(|b| b.0 > 0)
        .enumerate()
        .map(|(i, (_, b))| PersonRegion {
            bounds: PixelBox {
                x0: b[0] as f64,
                y0: b[1] as f64,
                x1: b[2] as f64,
                y1: b[3] as f64,
            },
            depth_m: 3.0 + i as f64,
        })
        .collect();
    (image, regions)
}
