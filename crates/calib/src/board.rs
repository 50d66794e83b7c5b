//! Chessboard calibration targets: the board's geometry (OpenCV's object points) and the
//! canonical order of its detected corners. Pure Rust; the detection itself is in the
//! `calibrate` module (feature `opencv`).
//!
//! Board frame: inner corner `(i, j)` is at `(i·square_m, j·square_m, 0)`, `i <
//! inner_corners[0]` (a row of the pattern), `j < inner_corners[1]`, z = x × y. The square
//! `(a, b)` covering `[a·s, (a+1)·s) × [b·s, (b+1)·s)` is black when `a + b` is even: the
//! square diagonally outside corner (0, 0) is black. A board whose two inner-corner counts
//! differ in parity (9×6) looks different turned by 180°, so its corner (0, 0) and axes
//! can be told from one image; a board with counts of equal parity (8×6, 9×7) cannot.

use crate::CalibError;

/// A chessboard calibration target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Board {
    /// Inner corners along the board's x (one pattern row) and y, OpenCV's pattern size
    /// (e.g. `[9, 6]`).
    pub inner_corners: [u32; 2],
    /// Side of one square, metres.
    pub square_m: f64,
}

/// Largest inner-corner count along one side accepted by [`Board::new`]: far more than any
/// printable board, small enough for every index to fit an `i32` (OpenCV's sizes).
pub const MAX_INNER_CORNERS: u32 = 1000;

impl Board {
    /// A board with at least 2×2 inner corners and a finite square side in (0, 10) m.
    pub fn new(inner_corners: [u32; 2], square_m: f64) -> Result<Board, CalibError> {
        let [nx, ny] = inner_corners;
        if !(2..=MAX_INNER_CORNERS).contains(&nx) || !(2..=MAX_INNER_CORNERS).contains(&ny) {
            return Err(CalibError::invalid(
                "board",
                format!("must have 2 to {MAX_INNER_CORNERS} inner corners per side, got {nx}x{ny}"),
            ));
        }
        if !(square_m.is_finite() && square_m > 0.0 && square_m < 10.0) {
            return Err(CalibError::invalid(
                "square_m",
                format!("must be in (0, 10) metres, got {square_m}"),
            ));
        }
        Ok(Board {
            inner_corners,
            square_m,
        })
    }

    /// Parses a pattern size `COLSxROWS` of inner corners (`9x6`).
    pub fn parse_inner_corners(text: &str) -> Result<[u32; 2], CalibError> {
        let bad = || {
            CalibError::invalid(
                "board",
                format!("must be the inner corners per row and per column, as 9x6, got {text:?}"),
            )
        };
        let (a, b) = text.trim().split_once(['x', 'X']).ok_or_else(bad)?;
        let a: u32 = a.trim().parse().map_err(|_| bad())?;
        let b: u32 = b.trim().parse().map_err(|_| bad())?;
        Ok([a, b])
    }

    /// Number of inner corners.
    pub fn num_corners(&self) -> usize {
        self.inner_corners[0] as usize * self.inner_corners[1] as usize
    }

    /// The inner corners in the board frame (metres), row by row: index `j·nx + i` is
    /// corner `(i, j)`, the order of OpenCV's `findChessboardCorners`.
    pub fn object_points(&self) -> Vec<[f64; 3]> {
        let [nx, ny] = self.inner_corners;
        (0..ny)
            .flat_map(|j| {
                (0..nx).map(move |i| {
                    [
                        f64::from(i) * self.square_m,
                        f64::from(j) * self.square_m,
                        0.0,
                    ]
                })
            })
            .collect()
    }

    /// True when the board looks different turned by 180° (inner-corner counts of
    /// different parity), so that one image fixes its frame.
    pub fn is_asymmetric(&self) -> bool {
        (self.inner_corners[0] + self.inner_corners[1]) % 2 == 1
    }

    /// `WxH`, the pattern size as the command line writes it.
    pub fn size_text(&self) -> String {
        format!("{}x{}", self.inner_corners[0], self.inner_corners[1])
    }
}

/// An 8-bit grey image, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct GrayImage {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// `width * height` grey levels, row-major.
    pub data: Vec<u8>,
}

impl GrayImage {
    /// The grey image of 8-bit RGB pixels (ITU-R BT.601 luma).
    pub fn from_rgb(width: u32, height: u32, rgb: &[u8]) -> GrayImage {
        let data = rgb
            .chunks_exact(3)
            .map(|p| {
                let y = 299 * u32::from(p[0]) + 587 * u32::from(p[1]) + 114 * u32::from(p[2]);
                // ≤ 255 · 1000 / 1000: fits a u8.
                u8::try_from((y + 500) / 1000).unwrap_or(u8::MAX)
            })
            .collect();
        GrayImage {
            width,
            height,
            data,
        }
    }

    /// Mean grey level of the pixels within `radius_px` (Chebyshev) of `uv_px`, clipped to
    /// the image; `None` when none is inside.
    fn mean_around(&self, uv_px: [f64; 2], radius_px: f64) -> Option<f64> {
        let (w, h) = (i64::from(self.width), i64::from(self.height));
        let r = radius_px.max(0.0);
        let (u0, u1) = ((uv_px[0] - r).round() as i64, (uv_px[0] + r).round() as i64);
        let (v0, v1) = ((uv_px[1] - r).round() as i64, (uv_px[1] + r).round() as i64);
        let (mut sum, mut n) = (0u64, 0u64);
        for v in v0.max(0)..=v1.min(h - 1) {
            for u in u0.max(0)..=u1.min(w - 1) {
                // In range: 0 ≤ u < w, 0 ≤ v < h.
                sum += u64::from(self.data[(v * w + u) as usize]);
                n += 1;
            }
        }
        (n > 0).then(|| sum as f64 / n as f64)
    }
}

/// Which way the board's z axis (x × y) points, seen from the camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoardZ {
    /// Away from the camera: OpenCV's convention for a board seen from its printed side
    /// (the board axes look like the image's u and v).
    AwayFromCamera,
    /// Towards the camera: a board lying on the floor whose z is the world's up.
    TowardCamera,
}

/// Puts detected corners (`board.num_corners()` of them, rows of `inner_corners[0]`, in
/// whatever order the detector found them) into the board's canonical order: z pointing
/// as `z` says and, on an asymmetric board ([`Board::is_asymmetric`]), the squares whose
/// index sum is even black. On a symmetric board only the handedness is fixed (corner (0, 0)
/// is one of two opposite corners).
///
/// The colour test compares the mean grey level of every inner square of even index sum
/// with that of the odd ones, so one badly lit square does not flip it.
pub fn canonical_corner_order(
    board: &Board,
    corners_px: &[[f64; 2]],
    image: &GrayImage,
    z: BoardZ,
) -> Result<Vec<[f64; 2]>, CalibError> {
    let [nx, ny] = [
        board.inner_corners[0] as usize,
        board.inner_corners[1] as usize,
    ];
    if corners_px.len() != nx * ny {
        return Err(CalibError::invalid(
            "corners",
            format!(
                "a {} board has {} inner corners, got {}",
                board.size_text(),
                nx * ny,
                corners_px.len()
            ),
        ));
    }
    let at = |i: usize, j: usize| corners_px[j * nx + i];
    // Handedness: image cross product of the board's x and y edges (u right, v down), > 0
    // when the board's axes look like u and v (z away from the camera).
    let (o, ex, ey) = (at(0, 0), at(nx - 1, 0), at(0, ny - 1));
    let cross = (ex[0] - o[0]) * (ey[1] - o[1]) - (ex[1] - o[1]) * (ey[0] - o[0]);
    let flip_handedness = match z {
        BoardZ::AwayFromCamera => cross < 0.0,
        BoardZ::TowardCamera => cross > 0.0,
    };
    // Colour: mean of squares with even index sum minus mean of odd ones, in the detected
    // order; negative (even squares darker) is right.
    let (mut sum, mut count) = ([0.0f64; 2], [0usize; 2]);
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let (a, b) = (at(i, j), at(i + 1, j + 1));
            let centre = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
            let diagonal = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
            // A patch a fifth of the square's diagonal wide: well inside the square.
            if let Some(mean) = image.mean_around(centre, 0.1 * diagonal) {
                sum[(i + j) % 2] += mean;
                count[(i + j) % 2] += 1;
            }
        }
    }
    let even_darker =
        count[0] > 0 && count[1] > 0 && sum[0] / count[0] as f64 <= sum[1] / count[1] as f64;
    // The four orderings that keep the pattern's shape: identity, flip x (i → nx-1-i),
    // flip y, both. A flip of x changes the square parity by nx, of y by ny (mod 2), and
    // each single flip reverses the handedness.
    let (flip_x, flip_y) = if flip_handedness {
        // One flip: x when that fixes the colours, else y.
        let parity_ok_after_x = even_darker == (nx % 2 == 0);
        if !board.is_asymmetric() || parity_ok_after_x {
            (true, false)
        } else {
            (false, true)
        }
    } else if board.is_asymmetric() && !even_darker {
        (true, true)
    } else {
        (false, false)
    };
    let mut out = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let si = if flip_x { nx - 1 - i } else { i };
            let sj = if flip_y { ny - 1 - j } else { j };
            out.push(at(si, sj));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A synthetic fronto-parallel board image: squares of `px` pixels, corner (0, 0) at
    /// `origin`, board x along +u and y along +v (z away from the camera).
    fn board_image(board: &Board, px: f64, origin: [f64; 2]) -> (GrayImage, Vec<[f64; 2]>) {
        let (w, h) = (200u32, 160u32);
        let mut data = vec![200u8; (w * h) as usize];
        for v in 0..h {
            for u in 0..w {
                let a = ((f64::from(u) - origin[0]) / px).floor() as i64;
                let b = ((f64::from(v) - origin[1]) / px).floor() as i64;
                let inside = a >= -1
                    && b >= -1
                    && a < i64::from(board.inner_corners[0])
                    && b < i64::from(board.inner_corners[1]);
                if inside && (a + b).rem_euclid(2) == 0 {
                    data[(v * w + u) as usize] = 20;
                }
            }
        }
        let corners = (0..board.inner_corners[1])
            .flat_map(|j| {
                (0..board.inner_corners[0]).map(move |i| {
                    [
                        origin[0] + f64::from(i) * px - 0.5,
                        origin[1] + f64::from(j) * px - 0.5,
                    ]
                })
            })
            .collect();
        (
            GrayImage {
                width: w,
                height: h,
                data,
            },
            corners,
        )
    }

    fn reorder(corners: &[[f64; 2]], nx: usize, ny: usize, fx: bool, fy: bool) -> Vec<[f64; 2]> {
        let mut out = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let si = if fx { nx - 1 - i } else { i };
                let sj = if fy { ny - 1 - j } else { j };
                out.push(corners[sj * nx + si]);
            }
        }
        out
    }

    #[test]
    fn every_detected_order_of_an_asymmetric_board_comes_back_canonical() {
        for inner in [[9u32, 6u32], [4, 3], [5, 8]] {
            let board = Board::new(inner, 0.04).expect("board");
            let (image, truth) = board_image(&board, 12.0, [30.0, 25.0]);
            let (nx, ny) = (inner[0] as usize, inner[1] as usize);
            for (fx, fy) in [(false, false), (true, false), (false, true), (true, true)] {
                let detected = reorder(&truth, nx, ny, fx, fy);
                let got = canonical_corner_order(&board, &detected, &image, BoardZ::AwayFromCamera)
                    .expect("order");
                assert_eq!(got, truth, "{inner:?} flips {fx} {fy}");
            }
        }
    }

    #[test]
    fn toward_camera_flips_the_handedness_keeping_the_colors() {
        let board = Board::new([9, 6], 0.04).expect("board");
        let (image, truth) = board_image(&board, 12.0, [30.0, 25.0]);
        let got =
            canonical_corner_order(&board, &truth, &image, BoardZ::TowardCamera).expect("order");
        assert_ne!(got, truth);
        // nx = 9 is odd: flipping x would swap the colours, so y is flipped.
        assert_eq!(got, reorder(&truth, 9, 6, false, true));
    }

    #[test]
    fn object_points_are_rows_of_the_first_count() {
        let board = Board::new([3, 2], 0.5).expect("board");
        let p = board.object_points();
        assert_eq!(p.len(), 6);
        assert_eq!(p[1], [0.5, 0.0, 0.0]);
        assert_eq!(p[3], [0.0, 0.5, 0.0]);
        assert!(board.is_asymmetric());
        assert!(!Board::new([8, 6], 0.5).expect("board").is_asymmetric());
    }

    #[test]
    fn bad_boards_name_the_field() {
        assert_eq!(Board::parse_inner_corners("9x6").expect("9x6"), [9, 6]);
        assert_eq!(Board::parse_inner_corners(" 7X5 ").expect("7X5"), [7, 5]);
        for bad in ["9", "9x", "x6", "9x6x2", "-9x6", "nine"] {
            let e = Board::parse_inner_corners(bad).expect_err(bad).to_string();
            assert!(e.starts_with("board "), "{e}");
        }
        let e = Board::new([1, 6], 0.04).expect_err("1 corner").to_string();
        assert!(e.contains("1x6"), "{e}");
        let e = Board::new([9, 6], 0.0).expect_err("0 m").to_string();
        assert!(e.starts_with("square_m "), "{e}");
    }

    #[test]
    fn gray_from_rgb_keeps_grey_levels() {
        let g = GrayImage::from_rgb(2, 1, &[0, 0, 0, 255, 255, 255]);
        assert_eq!(g.data, [0, 255]);
    }
}
