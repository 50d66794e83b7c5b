//! Foreign colours (`foreign_colour_density`): after the steps, arm labels on a colour the
//! person does not wear are the objects the person holds or touches.
//!
//! Why: a 2D parser labels what an arm holds or touches as arm — the parcel of a hand-over
//! on both palms, a robot link beside a person — and those points join the arm's clusters
//! (same label, touching), so M, R and N keep them. Sleeves are the shirt's colour and
//! hands and bare forearms the face's skin, so an arm point whose colour is rare on the
//! person's head and torso is not the person's. Measured on the tune sets of
//! docs/notes/2026-11-30-improved-refinement-tuning.md.
//!
//! What it cannot know: gloves, or sleeves of another colour than the shirt (a jacket
//! over a shirt whose front shows), are arms of a colour the head and torso do not have,
//! and become background; switch it off (0) for such people.

use bodyseg_core::math::{CHROMA_BINS, chroma_bin, near_chroma_bins, srgb_to_linear};
use bodyseg_core::{Class, Label};

/// Points a head or torso needs to serve as a colour reference.
pub const MIN_REFERENCE_POINTS: usize = 50;

/// Arm points whose brightest sRGB channel is below this are not judged: a dark pixel's
/// chromaticity is mostly noise and the floor below. Chosen on the tune sets: 0 cost the
/// synthetic parser errors 0.6 BIoU (naive, handover 7 + robot_cell 8 + single 9; a striped
/// shirt's dark stripes spread over many bins), 100 about 0.2, and it still catches the
/// bright parcels and robot links.
pub const MIN_BRIGHTNESS: u8 = 100;

/// Linear value added to each channel before the chromaticity: black's is grey's, and a dark
/// pixel does not jump between bins.
const LINEAR_FLOOR: f32 = 0.002;

/// Chromaticity bin of an 8-bit sRGB colour, in linear RGB ([`chroma_bin`]).
fn colour_bin(c: [u8; 3]) -> usize {
    chroma_bin(c.map(|x| srgb_to_linear(x) + LINEAR_FLOOR))
}

/// Every upper- or lower-arm label (of one person's points, `labels`, with their camera
/// colours `colours`) whose colour is rare on the person's head and on its torso becomes
/// `foreign`: background, or in a run unknown, which lets another person whose box holds the
/// point keep it as theirs (see `fuse_labels`). Rare: less than `min_density` of the head's
/// points, and less than that fraction of the torso's, have a chromaticity within one bin of
/// the point's (3 × 3 bins of [`CHROMA_BINS`] per axis, ±0.02). A head or torso of fewer
/// than [`MIN_REFERENCE_POINTS`] points counts for nothing; with neither, nothing changes.
/// Arm points darker than [`MIN_BRIGHTNESS`] are not judged.
///
/// The references are the head and torso labels, not the body tree's clusters: the tree's
/// torso cluster was tried (a robot link's patch labelled torso would not count) and was no
/// better on the tune sets, and where boxes overlap the tree's root can be the other
/// person's torso.
///
/// # Panics
/// When `colours` and `labels` differ in length.
pub fn drop_foreign_arms(
    labels: &mut [Label],
    colours: &[[u8; 3]],
    min_density: f32,
    foreign: Label,
) {
    assert_eq!(labels.len(), colours.len(), "one colour per label");
    let n = CHROMA_BINS;
    // Per reference part: the fraction of its points in each bin.
    let references: Vec<Vec<f32>> = [Class::Head, Class::Torso]
        .into_iter()
        .filter_map(|class| {
            let label = Label::from(class);
            let mut hist = vec![0f32; n * n];
            let mut count = 0usize;
            for (_, &c) in labels.iter().zip(colours).filter(|(l, _)| **l == label) {
                hist[colour_bin(c)] += 1.0;
                count += 1;
            }
            (count >= MIN_REFERENCE_POINTS).then(|| {
                hist.iter_mut().for_each(|h| *h /= count as f32);
                hist
            })
        })
        .collect();
    if references.is_empty() {
        return;
    }
    let arms = [Label::from(Class::UpperArms), Label::from(Class::LowerArms)];
    for (l, &c) in labels.iter_mut().zip(colours) {
        if !arms.contains(l) || c.iter().all(|&x| x < MIN_BRIGHTNESS) {
            continue;
        }
        let b = colour_bin(c);
        let worn = references.iter().any(|hist| {
            let density: f32 = near_chroma_bins(b).map(|k| hist[k]).sum();
            density >= min_density
        });
        if !worn {
            *l = foreign;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn l(c: Class) -> Label {
        Label::from(c)
    }

    fn drop(labels: &mut [Label], colours: &[[u8; 3]], min_density: f32) {
        drop_foreign_arms(labels, colours, min_density, Label::BACKGROUND);
    }

    /// A person: a skin face under dark hair, a blue shirt on the torso, and `arm` arm
    /// points of each given colour.
    fn person(arms: &[(Class, [u8; 3], usize)]) -> (Vec<Label>, Vec<[u8; 3]>) {
        let (mut labels, mut colours) = (Vec::new(), Vec::new());
        let mut add = |class, colour, count| {
            labels.extend(std::iter::repeat_n(l(class), count));
            colours.extend(std::iter::repeat_n(colour, count));
        };
        add(Class::Head, [200, 150, 120], 60); // face
        add(Class::Head, [40, 30, 25], 60); // hair
        add(Class::Torso, [40, 60, 160], 200); // shirt
        add(Class::Torso, [20, 30, 80], 100); // the shirt in shade
        for &(class, colour, count) in arms {
            add(class, colour, count);
        }
        (labels, colours)
    }

    #[test]
    fn an_orange_bar_labelled_forearm_goes_and_sleeves_and_hands_stay() {
        let orange = [215, 115, 15];
        let (mut labels, colours) = person(&[
            (Class::UpperArms, [45, 66, 170], 50), // sleeve, a little brighter
            (Class::LowerArms, [100, 75, 60], 30), // hand in shade: the face's hue
            (Class::LowerArms, orange, 40),        // a robot link
            (Class::UpperArms, orange, 10),
        ]);
        let before = labels.clone();
        drop(&mut labels, &colours, 0.03);
        for (i, (&b, &a)) in before.iter().zip(&labels).enumerate() {
            if colours[i] == orange {
                assert_eq!(a, Label::BACKGROUND, "point {i}: the orange bar goes");
            } else {
                assert_eq!(a, b, "point {i}: the person's own colours stay");
            }
        }
    }

    #[test]
    fn only_arms_change_and_a_reference_too_small_counts_for_nothing() {
        let green = [30, 200, 40];
        // A green torso patch and green legs: only arms are judged.
        let (mut labels, mut colours) = person(&[(Class::LowerArms, green, 20)]);
        labels.push(l(Class::UpperLegs));
        colours.push(green);
        drop(&mut labels, &colours, 0.03);
        assert!(labels[420..440].iter().all(|&x| x == Label::BACKGROUND));
        assert_eq!(labels[440], l(Class::UpperLegs));

        // A torso reference of 49 points and no head: no reference, nothing changes.
        let mut labels = vec![l(Class::Torso); 49];
        labels.push(l(Class::LowerArms));
        let mut colours = vec![[40, 60, 160]; 49];
        colours.push(green);
        let before = labels.clone();
        drop(&mut labels, &colours, 0.03);
        assert_eq!(labels, before);
    }

    #[test]
    fn every_torso_label_counts_as_worn() {
        // A parcel labelled lower arm, and a part of it the parser called torso: with 40 of
        // the torso's 340 points its colour is worn (a known limit); with 5 of 305 it is not.
        let orange = [215, 115, 15];
        for (patch, kept) in [(40, true), (5, false)] {
            let (mut labels, mut colours) = person(&[(Class::LowerArms, orange, 30)]);
            labels.extend(vec![l(Class::Torso); patch]);
            colours.extend(vec![orange; patch]);
            drop(&mut labels, &colours, 0.03);
            let want = if kept {
                l(Class::LowerArms)
            } else {
                Label::BACKGROUND
            };
            assert!(labels[420..450].iter().all(|&x| x == want), "patch {patch}");
            assert!(labels[450..].iter().all(|&x| x == l(Class::Torso)));
        }
    }

    #[test]
    fn a_dark_arm_point_is_not_judged() {
        // The same hue, bright and in deep shade: only the bright one is judged.
        let (mut labels, colours) = person(&[
            (Class::LowerArms, [215, 115, 15], 5),
            (Class::LowerArms, [90, 48, 6], 5),
        ]);
        drop(&mut labels, &colours, 0.03);
        assert!(labels[420..425].iter().all(|&x| x == Label::BACKGROUND));
        assert!(labels[425..].iter().all(|&x| x == l(Class::LowerArms)));
    }

    #[test]
    fn the_density_threshold_decides() {
        // 6 of the 120 head points (5 %) are the arm's colour.
        let tan = [180, 140, 60];
        let (mut labels, mut colours) = person(&[(Class::LowerArms, tan, 10)]);
        for c in colours.iter_mut().take(6) {
            *c = tan;
        }
        let start = labels.clone();
        drop(&mut labels, &colours, 0.04);
        assert_eq!(labels, start, "5 % of the head wears it: kept at 0.04");
        drop(&mut labels, &colours, 0.06);
        assert!(labels[420..].iter().all(|&x| x == Label::BACKGROUND));
    }
}
