//! The 7 body-part classes and the [`Label`] a point carries.

use serde::{Deserialize, Serialize};
use std::fmt;

/// Number of classes, background included.
pub const NUM_CLASSES: usize = 7;

/// A body-part class, Pascal-Person-Part order (what SCHP, CDCL and Grapy output).
/// Hands belong to [`Class::LowerArms`], feet to [`Class::LowerLegs`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[repr(u8)]
pub enum Class {
    /// Everything that is not a person (id 0).
    Background = 0,
    /// Head and neck (id 1).
    Head = 1,
    /// Torso (id 2).
    Torso = 2,
    /// Upper arms (id 3).
    UpperArms = 3,
    /// Lower arms with hands (id 4).
    LowerArms = 4,
    /// Upper legs (id 5).
    UpperLegs = 5,
    /// Lower legs with feet (id 6).
    LowerLegs = 6,
}

impl Class {
    /// All classes in id order.
    pub const ALL: [Class; NUM_CLASSES] = [
        Class::Background,
        Class::Head,
        Class::Torso,
        Class::UpperArms,
        Class::LowerArms,
        Class::UpperLegs,
        Class::LowerLegs,
    ];

    /// The 6 body classes (everything but background), in id order.
    pub const BODY: [Class; 6] = {
        let mut body = [Class::Head; 6];
        let mut i = 0;
        while i < body.len() {
            body[i] = Class::ALL[i + 1];
            i += 1;
        }
        body
    };

    /// The class with this id, if `id < 7`.
    pub fn from_id(id: u8) -> Option<Class> {
        Class::ALL.get(usize::from(id)).copied()
    }

    /// The class id (0..7), also its index in confusion matrices.
    pub fn id(self) -> u8 {
        self as u8
    }

    /// Index into per-class arrays.
    pub fn index(self) -> usize {
        self as usize
    }

    /// snake_case name used in files and reports.
    pub fn name(self) -> &'static str {
        match self {
            Class::Background => "background",
            Class::Head => "head",
            Class::Torso => "torso",
            Class::UpperArms => "upper_arms",
            Class::LowerArms => "lower_arms",
            Class::UpperLegs => "upper_legs",
            Class::LowerLegs => "lower_legs",
        }
    }

    /// Human-readable name for tables ("Lower arms").
    pub fn title(self) -> &'static str {
        match self {
            Class::Background => "Background",
            Class::Head => "Head",
            Class::Torso => "Torso",
            Class::UpperArms => "Upper arms",
            Class::LowerArms => "Lower arms",
            Class::UpperLegs => "Upper legs",
            Class::LowerLegs => "Lower legs",
        }
    }

    /// The class with this snake_case name.
    pub fn from_name(name: &str) -> Option<Class> {
        Class::ALL.into_iter().find(|c| c.name() == name)
    }

    /// Pascal-Person-Part palette colour (RGB).
    pub const fn color(self) -> [u8; 3] {
        match self {
            Class::Background => [0, 0, 0],
            Class::Head => [128, 0, 0],
            Class::Torso => [0, 128, 0],
            Class::UpperArms => [128, 128, 0],
            Class::LowerArms => [0, 0, 128],
            Class::UpperLegs => [128, 0, 128],
            Class::LowerLegs => [0, 128, 128],
        }
    }

    /// True for the 6 body classes.
    pub fn is_body(self) -> bool {
        self != Class::Background
    }
}

impl fmt::Display for Class {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The label of one point: a [`Class`], or unknown (the projection had no reliable
/// label for it, ALGORITHM.md §3). One byte, so clouds stay compact.
///
/// On disk (label images, PLY) unknown is written as id 255, as FORMATS.md says for
/// "not labelled"; inside the program use [`Label::class`] rather than the raw id.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[repr(transparent)]
pub struct Label(u8);

impl Label {
    /// The on-disk id of an unknown label.
    pub const UNKNOWN_ID: u8 = 255;
    /// No reliable label.
    pub const UNKNOWN: Label = Label(Self::UNKNOWN_ID);
    /// Background.
    pub const BACKGROUND: Label = Label(0);

    /// The label with this on-disk id: 0..7 is a class, 255 unknown, anything else `None`.
    pub fn from_id(id: u8) -> Option<Label> {
        (usize::from(id) < NUM_CLASSES || id == Self::UNKNOWN_ID).then_some(Label(id))
    }

    /// The label of an on-disk id, unknown for any id that names no class (no error:
    /// for ids known to be valid, or where unknown is the right reading of a bad one).
    #[inline]
    pub const fn from_id_or_unknown(id: u8) -> Label {
        // A select, not a branch: loops over whole images vectorise.
        Label(if (id as usize) < NUM_CLASSES {
            id
        } else {
            Self::UNKNOWN_ID
        })
    }

    /// The on-disk id (0..7, or 255 for unknown).
    pub fn id(self) -> u8 {
        self.0
    }

    /// The class, or `None` when unknown.
    pub fn class(self) -> Option<Class> {
        Class::from_id(self.0)
    }

    /// True when unknown.
    pub fn is_unknown(self) -> bool {
        self.0 == Self::UNKNOWN_ID
    }

    /// True for a body class (not background, not unknown).
    pub fn is_body(self) -> bool {
        self.class().is_some_and(Class::is_body)
    }

    /// How many places two label lists of the same points differ at (before and after a
    /// step, truth and prediction); a longer list's extra labels are not compared.
    pub fn count_differing(a: &[Label], b: &[Label]) -> usize {
        a.iter().zip(b).filter(|(a, b)| a != b).count()
    }

    /// Palette colour; unknown is drawn white so it stands out.
    #[inline]
    pub fn color(self) -> [u8; 3] {
        // A table rather than a match: PLY writing looks up every point's colour.
        LABEL_COLORS[usize::from(self.0)]
    }
}

/// [`Label::color`] by label id: the class palette, white for unknown (and for ids no
/// label has).
const LABEL_COLORS: [[u8; 3]; 256] = {
    let mut table = [[255u8; 3]; 256];
    let mut i = 0;
    while i < NUM_CLASSES {
        table[i] = Class::ALL[i].color();
        i += 1;
    }
    table
};

impl From<Class> for Label {
    fn from(c: Class) -> Label {
        Label(c.id())
    }
}

impl fmt::Debug for Label {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.class() {
            Some(c) => write!(f, "{c}"),
            None => f.write_str("unknown"),
        }
    }
}

impl fmt::Display for Label {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self, f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_round_trip_and_names_are_unique() {
        for c in Class::ALL {
            assert_eq!(Class::from_id(c.id()), Some(c));
            assert_eq!(Class::from_name(c.name()), Some(c));
            assert_eq!(Label::from(c).class(), Some(c));
        }
        assert_eq!(Class::from_id(7), None);
        assert_eq!(Label::from_id(7), None);
        assert!(Label::from_id(255).is_some_and(Label::is_unknown));
        assert!(!Label::UNKNOWN.is_body());
        assert!(!Label::BACKGROUND.is_body());
        assert!(Label::from(Class::Head).is_body());
    }

    #[test]
    fn count_differing_counts_changed_places() {
        let head = Label::from(Class::Head);
        let a = [head, Label::BACKGROUND, Label::UNKNOWN, head];
        let b = [head, head, Label::UNKNOWN, Label::UNKNOWN];
        assert_eq!(Label::count_differing(&a, &b), 2);
        assert_eq!(Label::count_differing(&a, &a), 0);
        assert_eq!(Label::count_differing(&a, &b[..1]), 0);
    }

    #[test]
    fn palette_matches_pascal_person_part() {
        assert_eq!(Class::LowerArms.color(), [0, 0, 128]);
        assert_eq!(Class::LowerLegs.color(), [0, 128, 128]);
        let mut colors: Vec<_> = Class::ALL.iter().map(|c| c.color()).collect();
        colors.dedup();
        assert_eq!(colors.len(), NUM_CLASSES);
        for c in Class::ALL {
            assert_eq!(Label::from(c).color(), c.color());
        }
        assert_eq!(Label::UNKNOWN.color(), [255, 255, 255]);
    }

    #[test]
    fn lossy_ids_are_unknown_outside_the_classes() {
        for id in 0..=255u8 {
            let want = Label::from_id(id).filter(|l| !l.is_unknown());
            let got = Label::from_id_or_unknown(id);
            match want {
                Some(l) => assert_eq!(got, l, "{id}"),
                None => assert!(got.is_unknown(), "{id}"),
            }
        }
    }
}
