//! Helpers shared by this crate's integration tests.
#![allow(dead_code)]

use bodyseg_core::rng::XorShift64Star;
use bodyseg_core::{Label, LabeledCloud, PointOrigin};
use std::io::Write;

/// A coordinate in about ±5 m with arbitrary low bits.
pub fn coord(rng: &mut XorShift64Star) -> f32 {
    (rng.next_u32() as f32 / u32::MAX as f32 - 0.5) * 10.0
}

/// A cloud of `n` points with every label id, tricky float values in front (signed zero,
/// subnormal, extremes) and camera colours.
pub fn sample_cloud(n: usize, seed: u64) -> LabeledCloud {
    let mut rng = XorShift64Star::new(seed);
    let tricky = [
        [0.0, -0.0, 0.1],
        [f32::MAX, f32::MIN, f32::MIN_POSITIVE],
        [1e-45, -1e-45, 1.0e-7],
        [123456.79, -0.3333333, 1.0e30],
    ];
    let ids = [0u8, 1, 2, 3, 4, 5, 6, 255];
    let mut cloud = LabeledCloud::default();
    let mut colors = Vec::new();
    for i in 0..n {
        let p = match tricky.get(i) {
            Some(&p) => p,
            None => [coord(&mut rng), coord(&mut rng), coord(&mut rng)],
        };
        cloud.positions_m.push(p);
        cloud
            .labels
            .push(Label::from_id(ids[i % ids.len()]).expect("valid id"));
        let c = rng.next_u32();
        colors.push([c as u8, (c >> 8) as u8, (c >> 16) as u8]);
        let pixel = if i == 1 {
            u32::MAX
        } else {
            rng.next_u32() % 512 * 424
        };
        cloud.origins.push(PointOrigin {
            camera: (i % 4) as u8 + if i == 2 { 200 } else { 0 },
            pixel,
        });
    }
    cloud.colors = Some(colors);
    cloud
}

/// Data encodings for [`PlyBuilder`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Enc {
    Ascii,
    Le,
    Be,
}

impl Enc {
    pub const ALL: [Enc; 3] = [Enc::Ascii, Enc::Le, Enc::Be];
    pub fn format(self) -> &'static str {
        match self {
            Enc::Ascii => "ascii",
            Enc::Le => "binary_little_endian",
            Enc::Be => "binary_big_endian",
        }
    }
}

/// Builds a PLY file by hand: header lines (after `format`) and rows of typed values.
pub struct PlyBuilder {
    pub enc: Enc,
    header: String,
    body: Vec<u8>,
}

impl PlyBuilder {
    /// `header` holds the lines between `format` and `end_header`.
    pub fn new(enc: Enc, header: &str) -> PlyBuilder {
        PlyBuilder {
            enc,
            header: format!("ply\nformat {} 1.0\n{}end_header\n", enc.format(), header),
            body: Vec::new(),
        }
    }

    /// One entry: `(type, value)` pairs in property order (a list is its count then its
    /// items).
    pub fn row(&mut self, values: &[(&str, f64)]) -> &mut Self {
        for &(ty, v) in values {
            self.value(ty, v);
        }
        if self.enc == Enc::Ascii {
            self.body.pop(); // the trailing space
            self.body.push(b'\n');
        }
        self
    }

    /// One entry that opens with `float x, y, z` (the usual vertex), then `rest` as in
    /// [`Self::row`].
    pub fn xyz_row(&mut self, xyz: [f64; 3], rest: &[(&str, f64)]) -> &mut Self {
        let mut values = vec![("float", xyz[0]), ("float", xyz[1]), ("float", xyz[2])];
        values.extend_from_slice(rest);
        self.row(&values)
    }

    /// `n` vertices (`k = 0..n`) of `float x, y, z, uchar red, green, blue`, each at the
    /// position and of the colour that `vertex(k)` gives.
    pub fn xyz_rgb_rows(
        &mut self,
        n: u32,
        vertex: impl Fn(f64) -> ([f64; 3], [f64; 3]),
    ) -> &mut Self {
        for k in 0..n {
            let (xyz, [r, g, b]) = vertex(f64::from(k));
            self.xyz_row(xyz, &[("uchar", r), ("uchar", g), ("uchar", b)]);
        }
        self
    }

    /// A file of one vertex per value of `labels`, each at the origin with its label
    /// stored as `label_type` (`uchar`, `uint`).
    pub fn labels_at_origin(enc: Enc, label_type: &str, labels: &[f64]) -> PlyBuilder {
        let header = format!(
            "element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
             property {label_type} label\n",
            labels.len()
        );
        let mut b = PlyBuilder::new(enc, &header);
        for &label in labels {
            b.xyz_row([0.0; 3], &[(label_type, label)]);
        }
        b
    }

    fn value(&mut self, ty: &str, v: f64) {
        macro_rules! bin {
            ($x:expr) => {{
                let x = $x;
                if self.enc == Enc::Be {
                    self.body.extend_from_slice(&x.to_be_bytes())
                } else {
                    self.body.extend_from_slice(&x.to_le_bytes())
                }
            }};
        }
        match self.enc {
            Enc::Ascii => {
                write!(self.body, "{v} ").expect("write to Vec");
            }
            Enc::Le | Enc::Be => match ty {
                "char" | "int8" => bin!(v as i8),
                "uchar" | "uint8" => bin!(v as u8),
                "short" | "int16" => bin!(v as i16),
                "ushort" | "uint16" => bin!(v as u16),
                "int" | "int32" => bin!(v as i32),
                "uint" | "uint32" => bin!(v as u32),
                "float" | "float32" => bin!(v as f32),
                "double" | "float64" => bin!(v),
                other => panic!("unknown type {other}"),
            },
        }
    }

    pub fn bytes(&self) -> Vec<u8> {
        let mut out = self.header.clone().into_bytes();
        out.extend_from_slice(&self.body);
        out
    }

    pub fn header_len(&self) -> usize {
        self.header.len()
    }
}
