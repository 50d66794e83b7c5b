//! Renders frames of a preset and prints the time per frame (for profiling, e.g. under
//! `valgrind --tool=callgrind`): `cargo run --release -p bodyseg-synth --example
//! render_frames -- robot_cell 5`.

use bodyseg_synth::{Synth, preset};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("robot_cell", String::as_str);
    let frames: usize = args.get(2).and_then(|n| n.parse().ok()).unwrap_or(5);
    let synth = match preset(name).and_then(|c| Synth::new(c, 1)) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let start = Instant::now();
    for i in 0..frames {
        std::hint::black_box(synth.frame(i));
    }
    let per = start.elapsed().as_secs_f64() * 1e3 / frames as f64;
    println!("{name}: {per:.1} ms per frame ({frames} frames)");
}
