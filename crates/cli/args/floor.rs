//! `--ground` and `--up` of `boxes` and `import cloud`.

use bodyseg_pipeline::FloorHint;
use clap::Args;

/// `--ground` and `--up`: the floor of a cloud, when the user knows it.
#[derive(Debug, Args)]
pub struct FloorArgs {
    /// The floor of the cloud: the plane a*x + b*y + c*z + d = 0 in the cloud's frame,
    /// metres (PCL's ground coefficients) [default: found]
    #[arg(long, value_name = "A,B,C,D", value_parser = parse_plane, allow_hyphen_values = true)]
    pub ground: Option<[f32; 4]>,

    /// The axis of the cloud's frame that points up, roughly (within 45 degrees): x, y,
    /// z, -x, -y or -z (a camera's optical frame: -y) [default: found]
    #[arg(long, value_name = "AXIS", value_parser = parse_up, allow_hyphen_values = true)]
    pub up: Option<bodyseg_pipeline::Up>,
}

impl FloorArgs {
    /// The pipeline's floor hint.
    pub fn hint(&self) -> FloorHint {
        FloorHint {
            ground: self.ground,
            up: self.up,
        }
    }

    /// Whether either flag is given.
    pub fn given(&self) -> bool {
        self.ground.is_some() || self.up.is_some()
    }
}

/// `--ground a,b,c,d`: four finite numbers, (a, b, c) not all zero.
fn parse_plane(text: &str) -> std::result::Result<[f32; 4], String> {
    let values: Vec<f32> = text
        .split(',')
        .map(|v| {
            v.trim()
                .parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("'{}' is not a finite number", v.trim()))
        })
        .collect::<std::result::Result<_, _>>()?;
    let [a, b, c, d] = values[..] else {
        return Err(format!(
            "expected four numbers a,b,c,d (the plane a*x + b*y + c*z + d = 0), got {}",
            values.len()
        ));
    };
    if a == 0.0 && b == 0.0 && c == 0.0 {
        return Err("a, b and c are all 0: no plane".into());
    }
    Ok([a, b, c, d])
}

/// `--up AXIS`.
fn parse_up(text: &str) -> std::result::Result<bodyseg_pipeline::Up, String> {
    text.parse()
}
