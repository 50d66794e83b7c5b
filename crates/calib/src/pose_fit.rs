//! A rigid pose fitted to the corners of one board seen by several sensors of a camera at
//! once (Levenberg-Marquardt on the pixel reprojection error). Pure Rust: the sensors'
//! intrinsics and relative poses are known, only the board's pose moves.

use crate::{Board, CalibError, Intrinsics, Pose};

/// Iterations [`refine_board_pose`] may take; it converges in a handful from a `solvePnP`
/// start.
const MAX_ITERATIONS: usize = 50;

/// Step of the numeric derivatives: radians for the rotation, metres for the
/// translation; small against a board pose, large against f64 rounding.
const DERIVATIVE_STEP: f64 = 1e-7;

/// The iteration stops when a step moves the pose by less than this (radians and metres).
const STEP_TOLERANCE: f64 = 1e-12;

/// The board's corners as one sensor of the camera saw them.
#[derive(Clone, Copy, Debug)]
pub struct SensorCorners<'a> {
    /// The sensor's intrinsics.
    pub intrinsics: &'a Intrinsics,
    /// Maps the reference (depth) sensor's frame into this sensor's.
    pub sensor_from_reference: Pose,
    /// The board's inner corners in this sensor's image, canonical order, pixels.
    pub corners_px: &'a [[f64; 2]],
}

/// Rotation matrix of a rotation vector (axis × angle, radians): Rodrigues' formula.
fn rotation_from_vector(w: [f64; 3]) -> [[f64; 3]; 3] {
    let theta = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
    let k = [[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]];
    // sin θ / θ and (1 − cos θ) / θ², by their series near 0.
    let (a, b) = if theta < 1e-8 {
        (1.0, 0.5)
    } else {
        (theta.sin() / theta, (1.0 - theta.cos()) / (theta * theta))
    };
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let kk: f64 = (0..3).map(|m| k[i][m] * k[m][j]).sum();
            r[i][j] = f64::from(u8::from(i == j)) + a * k[i][j] + b * kk;
        }
    }
    r
}

/// `pose` moved by `delta` = (rotation vector, translation), applied on the left:
/// `exp(w) · R`, `t + v`.
fn perturbed(pose: &Pose, delta: &[f64; 6]) -> Result<Pose, CalibError> {
    let dr = rotation_from_vector([delta[0], delta[1], delta[2]]);
    let r = pose.rotation();
    let t = pose.translation_m();
    let mut out = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            out[i][j] = (0..3).map(|m| dr[i][m] * r[m][j]).sum();
        }
    }
    Pose::from_rotation_translation(out, [t[0] + delta[3], t[1] + delta[4], t[2] + delta[5]])
}

/// The stacked pixel residuals (projected − observed) of every corner of every sensor;
/// `None` when a corner falls behind a sensor.
fn residuals(
    board: &Board,
    views: &[SensorCorners<'_>],
    reference_from_board: &Pose,
) -> Option<Vec<f64>> {
    let object = board.object_points();
    let mut out = Vec::new();
    for view in views {
        let sensor_from_board = view.sensor_from_reference.compose(reference_from_board);
        for (p, c) in object.iter().zip(view.corners_px) {
            let uv = view
                .intrinsics
                .project(sensor_from_board.transform_point(*p))?;
            out.push(uv[0] - c[0]);
            out.push(uv[1] - c[1]);
        }
    }
    Some(out)
}

/// Solves the 6×6 system `a · x = b` by Gaussian elimination with partial pivoting.
fn solve6(mut a: [[f64; 6]; 6], mut b: [f64; 6]) -> Option<[f64; 6]> {
    for col in 0..6 {
        let pivot = (col..6).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() < 1e-300 {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        for row in col + 1..6 {
            let f = a[row][col] / a[col][col];
            for k in col..6 {
                a[row][k] -= f * a[col][k];
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; 6];
    for row in (0..6).rev() {
        let s: f64 = (row + 1..6).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - s) / a[row][row];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Refines `reference_from_board` (e.g. from `solvePnP` on one sensor) so that the board's
/// corners reproject onto every sensor's observations with the least squared pixel error
/// (Levenberg-Marquardt, numeric Jacobian). Returns the refined pose.
pub fn refine_board_pose(
    board: &Board,
    views: &[SensorCorners<'_>],
    reference_from_board: &Pose,
) -> Result<Pose, CalibError> {
    if let Some(v) = views
        .iter()
        .find(|v| v.corners_px.len() != board.num_corners())
    {
        return Err(CalibError::invalid(
            "corners",
            format!(
                "a {} board has {} inner corners, got {}",
                board.size_text(),
                board.num_corners(),
                v.corners_px.len()
            ),
        ));
    }
    let cost = |r: &[f64]| r.iter().map(|x| x * x).sum::<f64>();
    let mut pose = *reference_from_board;
    let mut r = residuals(board, views, &pose).ok_or_else(|| {
        CalibError::invalid("pose", "the board is behind a sensor at the starting pose")
    })?;
    let mut lambda = 1e-3;
    for _ in 0..MAX_ITERATIONS {
        // Numeric Jacobian, one column per pose parameter.
        let mut jac = Vec::with_capacity(6);
        for k in 0..6 {
            let mut d = [0.0; 6];
            d[k] = DERIVATIVE_STEP;
            let moved = residuals(board, views, &perturbed(&pose, &d)?)
                .ok_or_else(|| CalibError::invalid("pose", "the board moved behind a sensor"))?;
            jac.push(
                moved
                    .iter()
                    .zip(&r)
                    .map(|(a, b)| (a - b) / DERIVATIVE_STEP)
                    .collect::<Vec<_>>(),
            );
        }
        let mut jtj = [[0.0; 6]; 6];
        let mut jtr = [0.0; 6];
        for i in 0..6 {
            for j in 0..6 {
                jtj[i][j] = jac[i].iter().zip(&jac[j]).map(|(a, b)| a * b).sum();
            }
            jtr[i] = -jac[i].iter().zip(&r).map(|(a, b)| a * b).sum::<f64>();
        }
        let mut improved = false;
        for _ in 0..10 {
            let mut damped = jtj;
            for (i, row) in damped.iter_mut().enumerate() {
                row[i] += lambda * jtj[i][i].max(1e-12);
            }
            let Some(step) = solve6(damped, jtr) else {
                lambda *= 10.0;
                continue;
            };
            let candidate = perturbed(&pose, &step)?;
            match residuals(board, views, &candidate) {
                Some(rc) if cost(&rc) < cost(&r) => {
                    let size = step.iter().map(|x| x.abs()).fold(0.0, f64::max);
                    pose = candidate;
                    r = rc;
                    lambda = (lambda / 10.0).max(1e-12);
                    improved = size > STEP_TOLERANCE;
                    break;
                }
                _ => lambda *= 10.0,
            }
        }
        if !improved {
            break;
        }
    }
    Ok(pose)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sensor(fx: f64) -> Intrinsics {
        Intrinsics::pinhole(640, 480, fx, fx, 320.0, 240.0).with_distortion(
            crate::Distortion::BrownConrady([0.05, -0.1, 0.001, -0.001, 0.02]),
        )
    }

    fn project_all(board: &Board, i: &Intrinsics, sensor_from_board: &Pose) -> Vec<[f64; 2]> {
        board
            .object_points()
            .iter()
            .map(|p| {
                i.project(sensor_from_board.transform_point(*p))
                    .expect("in front")
            })
            .collect()
    }

    /// Exact corners from two sensors: a perturbed start comes back to the true pose.
    #[test]
    fn refinement_recovers_the_true_pose_from_a_perturbed_start() {
        let board = Board::new([9, 6], 0.1).expect("board");
        let truth = perturbed(
            &Pose::from_rotation_translation(
                [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                [-0.4, -0.2, 2.5],
            )
            .expect("pose"),
            &[0.3, -0.2, 0.1, 0.0, 0.0, 0.0],
        )
        .expect("pose");
        let (a, b) = (sensor(500.0), sensor(700.0));
        let b_from_a = Pose::from_rotation_translation(
            rotation_from_vector([0.01, -0.02, 0.005]),
            [-0.052, 0.001, 0.002],
        )
        .expect("pose");
        let ca = project_all(&board, &a, &truth);
        let cb = project_all(&board, &b, &b_from_a.compose(&truth));
        let views = [
            SensorCorners {
                intrinsics: &a,
                sensor_from_reference: Pose::identity(),
                corners_px: &ca,
            },
            SensorCorners {
                intrinsics: &b,
                sensor_from_reference: b_from_a,
                corners_px: &cb,
            },
        ];
        let start = perturbed(&truth, &[0.02, -0.01, 0.015, 0.03, -0.02, 0.05]).expect("pose");
        let got = refine_board_pose(&board, &views, &start).expect("refine");
        for (g, t) in got.translation_m().iter().zip(truth.translation_m()) {
            // Exact data: the fit lands on the truth to well below a micrometre.
            assert!((g - t).abs() < 1e-7, "{g} vs {t}");
        }
        for (gr, tr) in got.rotation().iter().zip(truth.rotation()) {
            for (g, t) in gr.iter().zip(tr) {
                assert!((g - t).abs() < 1e-8, "{g} vs {t}");
            }
        }
    }

    #[test]
    fn small_rotation_vectors_match_the_series() {
        let r = rotation_from_vector([0.0, 0.0, 1e-9]);
        assert!((r[0][1] + 1e-9).abs() < 1e-15);
        let r = rotation_from_vector([0.0, 0.0, std::f64::consts::FRAC_PI_2]);
        assert!((r[0][1] + 1.0).abs() < 1e-12 && r[0][0].abs() < 1e-12);
    }
}
