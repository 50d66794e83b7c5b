//! Two tools for changing the refinement's speed without changing its results.
//!
//! `digest`: prints one line per (cloud, configuration) with a 64-bit FNV-1a digest of
//! what the refinement (or DBSCAN alone) gave every point. Run it on two builds (e.g. main
//! and a branch) and `diff` the outputs: equal lines mean bit-identical labels, clusters
//! and core flags. Clouds: the synth clouds of the benches (`benches/common/synth_cloud.rs`,
//! seed 1) at `--sizes` (default 30000,100000,300000) and the testkit cloud at 30000;
//! configurations: the paper's M-R-N and each step set, the five of `Steps::PAPER` in one
//! `refine_variants` call, the contact graph, the coverage tree, weighted and probability
//! noise (made-up probabilities in strips), the improved settings, a finite label penalty,
//! other eps / min_points, two overlapping boxes, and DBSCAN alone.
//!
//! ```text
//! cargo run --release -p bodyseg-refine --example refine_check -- digest > branch.txt
//! ```
//!
//! `save --points N --out DIR` writes the synth cloud of N points (`points.f32`,
//! `labels.u8`, `box.txt`); `once --load DIR [--repeat K] [--steps M-R-N]` reads it and
//! runs `refine` K times (default 1; 0 loads only): a small process for
//! `valgrind --tool=callgrind` (one refinement = the instructions of `--repeat 1` minus
//! those of `--repeat 0`) or `perf record`.

/// The same allocator as the `bodyseg` binary.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use bodyseg_core::{Label, LabeledCloud, PersonBox, PointOrigin};
use bodyseg_refine::{
    DbscanParams, GraphMode, NoiseMode, PointEvidence, RefineConfig, Steps, TreeMode, dbscan,
    refine, refine_variants_with,
};
use bodyseg_testkit::human_cloud;
use std::path::Path;

#[path = "../benches/common/synth_cloud.rs"]
#[allow(dead_code)] // The counts of flying pixels and label errors are not printed here.
mod synth_cloud;

#[path = "../benches/common/alloc.rs"]
mod alloc;

#[path = "../benches/common/evidence.rs"]
mod evidence;

type Error = Box<dyn std::error::Error>;

/// FNV-1a, 64 bits.
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 ^= u64::from(x);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn labels(&mut self, l: &[Label]) {
        for x in l {
            self.bytes(&[x.id()]);
        }
    }
}

fn main() -> Result<(), Error> {
    alloc::keep_freed_memory();
    let mut args = std::env::args().skip(1);
    let cmd = args.next().unwrap_or_default();
    let mut points = 100_000usize;
    let mut sizes = vec![30_000usize, 100_000, 300_000];
    let mut dir = std::path::PathBuf::from("target/refine_check");
    let mut repeat = 1usize;
    let mut steps = Steps::MRN;
    while let Some(a) = args.next() {
        let mut v = || args.next().ok_or_else(|| format!("{a} needs a value"));
        match a.as_str() {
            "--points" => points = v()?.parse()?,
            "--sizes" => sizes = v()?.split(',').map(str::parse).collect::<Result<_, _>>()?,
            "--out" | "--load" => dir = v()?.into(),
            "--repeat" => repeat = v()?.parse()?,
            "--steps" => steps = v()?.parse()?,
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    match cmd.as_str() {
        "digest" => digest(&sizes),
        "save" => save(points, &dir),
        "once" => once(&dir, repeat, steps),
        _ => Err("usage: refine_check digest|save|once [options] (see the file's doc)".into()),
    }
}

fn digest(sizes: &[usize]) -> Result<(), Error> {
    let mut clouds: Vec<(String, LabeledCloud, PersonBox)> = Vec::new();
    for &n in sizes {
        let p = synth_cloud::synth_person_cloud(n, 1)?;
        clouds.push((format!("synth{n}"), p.cloud, p.person_box));
    }
    let p = human_cloud(30_000, 1);
    clouds.push(("testkit30000".into(), p.cloud, p.person_box));
    let paper = RefineConfig::default();
    let probability = evidence::probability_config(&paper);
    let improved = RefineConfig {
        eps_m: 0.045,
        noise_doubt_radius_m: 0.15,
        remove_through_noise: true,
        merge_into_background: true,
        floor_contact_m: 0.006,
        smooth_radius_m: 0.05,
        ..probability.clone()
    };
    let with_steps = |s: &str| -> Result<RefineConfig, Error> {
        Ok(RefineConfig {
            steps: s.parse()?,
            ..paper.clone()
        })
    };
    let configs: Vec<(&str, RefineConfig, bool)> = vec![
        ("M-R-N", paper.clone(), false),
        ("M", with_steps("M")?, false),
        ("N", with_steps("N")?, false),
        ("M-N", with_steps("M-N")?, false),
        (
            "contact",
            RefineConfig {
                graph: GraphMode::Contact,
                ..paper.clone()
            },
            false,
        ),
        (
            "coverage",
            RefineConfig {
                tree: TreeMode::Coverage,
                ..paper.clone()
            },
            false,
        ),
        (
            "weighted",
            RefineConfig {
                noise: NoiseMode::Weighted,
                ..paper.clone()
            },
            false,
        ),
        ("probability", probability, true),
        ("improved", improved, true),
        (
            "penalty0.02",
            RefineConfig {
                label_penalty_m: 0.02,
                ..paper.clone()
            },
            false,
        ),
        (
            "eps0.03-min10",
            RefineConfig {
                eps_m: 0.03,
                min_points: 10,
                ..paper.clone()
            },
            false,
        ),
        (
            "eps0.08-min120",
            RefineConfig {
                eps_m: 0.08,
                min_points: 120,
                ..paper.clone()
            },
            false,
        ),
        (
            "min1",
            RefineConfig {
                min_points: 1,
                ..paper.clone()
            },
            false,
        ),
    ];
    for (name, cloud, person_box) in &clouds {
        let probs = evidence::strip_probs(&cloud.positions_m);
        // All five configurations of the paper from one clustering.
        let v = refine_variants_with(
            cloud,
            PointEvidence::default(),
            std::slice::from_ref(person_box),
            &paper,
            &Steps::PAPER,
            true,
        )?;
        let mut h = Fnv::new();
        for l in &v.labels {
            h.labels(l);
        }
        hash_clusters(&mut h, &v.clusters);
        println!("{name} paper-variants {:016x}", h.0);
        // Two overlapping boxes: the halves of the person's along x, 10 cm of overlap.
        let halves = split_box(person_box);
        for (cname, cfg, with_probs) in &configs {
            let evidence = PointEvidence {
                label_probs: with_probs.then_some(probs.as_slice()),
                ..Default::default()
            };
            for (bname, boxes) in [
                ("one-box", std::slice::from_ref(person_box)),
                ("two-boxes", &halves[..]),
            ] {
                let v = refine_variants_with(cloud, evidence, boxes, cfg, &[cfg.steps], true)?;
                let mut h = Fnv::new();
                h.labels(&v.labels[0]);
                hash_clusters(&mut h, &v.clusters);
                println!("{name} {cname} {bname} {:016x}", h.0);
            }
        }
        for (pname, params) in [
            ("dbscan", paper.dbscan_params()),
            (
                "dbscan-penalty0.02",
                DbscanParams {
                    label_penalty_m: 0.02,
                    ..paper.dbscan_params()
                },
            ),
            (
                "dbscan-eps0.03-min10",
                DbscanParams {
                    eps_m: 0.03,
                    min_points: 10,
                    ..paper.dbscan_params()
                },
            ),
        ] {
            let c = dbscan(&cloud.positions_m, &cloud.labels, &params);
            let mut h = Fnv::new();
            for (k, core) in c.cluster_of.iter().zip(&c.is_core) {
                h.bytes(&k.map_or(u32::MAX, |k| k).to_le_bytes());
                h.bytes(&[u8::from(*core)]);
            }
            h.labels(&c.cluster_labels);
            println!("{name} {pname} {:016x}", h.0);
        }
    }
    Ok(())
}

fn hash_clusters(h: &mut Fnv, clusters: &[Option<(u32, u32)>]) {
    for c in clusters {
        let (p, k) = c.unwrap_or((u32::MAX, u32::MAX));
        h.bytes(&p.to_le_bytes());
        h.bytes(&k.to_le_bytes());
    }
}

/// The two halves of `b` along its own x axis, each 5 cm longer toward the other.
fn split_box(b: &PersonBox) -> [PersonBox; 2] {
    let (sin, cos) = b.yaw_rad.sin_cos();
    let hx = b.half_extents_m[0];
    let half = [hx / 2.0 + 0.05, b.half_extents_m[1], b.half_extents_m[2]];
    let shift = hx / 2.0;
    let at = |s: f32| {
        [
            b.center_m[0] + s * shift * cos,
            b.center_m[1] + s * shift * sin,
            b.center_m[2],
        ]
    };
    [
        PersonBox {
            id: 0,
            center_m: at(-1.0),
            half_extents_m: half,
            yaw_rad: b.yaw_rad,
        },
        PersonBox {
            id: 1,
            center_m: at(1.0),
            half_extents_m: half,
            yaw_rad: b.yaw_rad,
        },
    ]
}

fn save(points: usize, dir: &Path) -> Result<(), Error> {
    let p = synth_cloud::synth_person_cloud(points, 1)?;
    std::fs::create_dir_all(dir)?;
    let xyz: Vec<u8> = p
        .cloud
        .positions_m
        .iter()
        .flatten()
        .flat_map(|c| c.to_le_bytes())
        .collect();
    std::fs::write(dir.join("points.f32"), xyz)?;
    let ids: Vec<u8> = p.cloud.labels.iter().map(|l| l.id()).collect();
    std::fs::write(dir.join("labels.u8"), ids)?;
    let b = &p.person_box;
    let v = [
        b.center_m[0],
        b.center_m[1],
        b.center_m[2],
        b.half_extents_m[0],
        b.half_extents_m[1],
        b.half_extents_m[2],
        b.yaw_rad,
    ];
    let text: Vec<String> = v.iter().map(|x| format!("{x:e}")).collect();
    std::fs::write(dir.join("box.txt"), text.join(" "))?;
    Ok(())
}

fn once(dir: &Path, repeat: usize, steps: Steps) -> Result<(), Error> {
    let xyz = std::fs::read(dir.join("points.f32"))?;
    let positions_m: Vec<[f32; 3]> = xyz
        .chunks_exact(12)
        .map(|c| {
            let f = |k: usize| f32::from_le_bytes([c[k], c[k + 1], c[k + 2], c[k + 3]]);
            [f(0), f(4), f(8)]
        })
        .collect();
    let labels: Vec<Label> = std::fs::read(dir.join("labels.u8"))?
        .into_iter()
        .map(|id| Label::from_id(id).unwrap_or(Label::UNKNOWN))
        .collect();
    let v: Vec<f32> = std::fs::read_to_string(dir.join("box.txt"))?
        .split_whitespace()
        .map(str::parse)
        .collect::<Result<_, _>>()?;
    let [cx, cy, cz, hx, hy, hz, yaw] = v[..] else {
        return Err("box.txt: 7 numbers expected".into());
    };
    let n = positions_m.len();
    let cloud = LabeledCloud {
        positions_m,
        labels,
        colors: None,
        origins: (0..n as u32)
            .map(|pixel| PointOrigin { camera: 0, pixel })
            .collect(),
    };
    let boxes = [PersonBox {
        id: 0,
        center_m: [cx, cy, cz],
        half_extents_m: [hx, hy, hz],
        yaw_rad: yaw,
    }];
    let cfg = RefineConfig {
        steps,
        ..RefineConfig::default()
    };
    // `--repeat 0` loads only: under callgrind, the difference to `--repeat 1` is one
    // refinement.
    let mut best = f64::INFINITY;
    for _ in 0..repeat {
        let t = std::time::Instant::now();
        let r = refine(&cloud, &boxes, &cfg)?;
        best = best.min(t.elapsed().as_secs_f64());
        std::hint::black_box(r);
    }
    println!(
        "{n} points, {} threads, best of {repeat}: {:.3} ms",
        rayon::current_num_threads(),
        best * 1e3
    );
    Ok(())
}
