//! The static scene: room materials, a table, boxes and a robot arm made of cylinders that
//! moves over the frames. Everything here is class background (`Owner::Scene`).

use crate::config::StaticSceneConfig;
use crate::geometry::{
    Material, Owner, Primitive, Shape, Texture, V3, add, frame_from_axis, rotate_z, scale,
};
use crate::people::FloorObstacle;
use crate::render::Room;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The static part of a scene, fixed for a sequence.
#[derive(Clone, Debug)]
pub struct StaticScene {
    room: Option<Room>,
    /// Groups of primitives that never move (table, each box).
    fixed: Vec<Vec<Primitive>>,
    robot: Option<RobotArm>,
    obstacles: Vec<FloorObstacle>,
}

/// A 3-link arm on a pedestal; joint angles follow slow sinusoids.
#[derive(Clone, Debug)]
struct RobotArm {
    base: [f32; 2],
    /// Yaw of the arm's working direction (towards the workspace), radians.
    yaw: f32,
    phase: [f32; 3],
    material: Material,
    joint_material: Material,
}

impl StaticScene {
    /// The scene of `config`, with random placements deterministic in `seed`.
    pub fn new(config: &StaticSceneConfig, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x0005_CE4E_0000_0001);
        let half = config.room_half_m as f32;
        let room = (config.floor || config.walls).then(|| Room {
            floor: config.floor.then_some(Material {
                albedo: [0.46, 0.44, 0.40],
                texture: Texture::Checker {
                    cell_m: 0.6,
                    other: [0.36, 0.35, 0.33],
                },
            }),
            walls: config.walls.then_some(Material {
                albedo: [0.70, 0.68, 0.62],
                texture: Texture::Noise {
                    cell_m: 0.25,
                    amplitude: 0.25,
                },
            }),
            half_m: half,
        });
        let mut fixed = Vec::new();
        let mut obstacles = Vec::new();
        if config.table {
            // A table beside the people, on the +y side of the workspace.
            let center = [
                rng.random_range(-0.3..0.3),
                1.25 + rng.random_range(-0.1..0.1),
            ];
            fixed.push(table(center, rng.random_range(-0.3..0.3)));
            obstacles.push(FloorObstacle {
                center_m: center,
                radius_m: 0.75,
            });
        }
        let robot = config.robot_arm.then(|| {
            let base = [1.35, -0.9];
            obstacles.push(FloorObstacle {
                center_m: base,
                radius_m: 0.55,
            });
            RobotArm {
                base,
                yaw: (-base[1]).atan2(-base[0]),
                phase: [
                    rng.random_range(0.0..std::f32::consts::TAU),
                    rng.random_range(0.0..std::f32::consts::TAU),
                    rng.random_range(0.0..std::f32::consts::TAU),
                ],
                material: Material {
                    albedo: [0.85, 0.45, 0.05],
                    texture: Texture::Plain,
                },
                joint_material: Material::plain([0.15, 0.15, 0.17]),
            }
        });
        for _ in 0..config.boxes {
            // Boxes stand near the room's edge ring, outside the people's area.
            let angle: f32 = rng.random_range(0.0..std::f32::consts::TAU);
            let radius = rng.random_range(1.6..2.2f32).min(half - 0.4);
            let center = [radius * angle.cos(), radius * angle.sin()];
            let size = [
                rng.random_range(0.3..0.6f32),
                rng.random_range(0.3..0.6f32),
                rng.random_range(0.3..0.9f32),
            ];
            let tint = rng.random_range(0.0..1.0f32);
            let albedo = [0.45 + 0.2 * tint, 0.33 + 0.1 * tint, 0.2];
            let yaw = rng.random_range(0.0..1.5f32);
            let axes = [
                rotate_z([1.0, 0.0, 0.0], yaw),
                rotate_z([0.0, 1.0, 0.0], yaw),
                [0.0, 0.0, 1.0],
            ];
            fixed.push(vec![Primitive {
                shape: Shape::Box {
                    center: [center[0], center[1], size[2] / 2.0],
                    axes,
                    half: [size[0] / 2.0, size[1] / 2.0, size[2] / 2.0],
                },
                owner: Owner::Scene,
                material: Material {
                    albedo,
                    texture: Texture::Noise {
                        cell_m: 0.08,
                        amplitude: 0.15,
                    },
                },
            }]);
            obstacles.push(FloorObstacle {
                center_m: center,
                radius_m: 0.45,
            });
        }
        StaticScene {
            room,
            fixed,
            robot,
            obstacles,
        }
    }

    /// Floor and walls.
    pub fn room(&self) -> Option<Room> {
        self.room
    }

    /// Circles people must stay out of.
    pub fn obstacles(&self) -> &[FloorObstacle] {
        &self.obstacles
    }

    /// The scene's primitive groups at time `t_s` (the robot arm moves).
    pub fn groups_at(&self, t_s: f64) -> Vec<Vec<Primitive>> {
        let mut groups = self.fixed.clone();
        if let Some(robot) = &self.robot {
            groups.push(robot.primitives_at(t_s as f32));
        }
        groups
    }
}

fn table(center: [f32; 2], yaw: f32) -> Vec<Primitive> {
    let wood = Material {
        albedo: [0.55, 0.38, 0.22],
        texture: Texture::Noise {
            cell_m: 0.05,
            amplitude: 0.2,
        },
    };
    let metal = Material::plain([0.25, 0.25, 0.27]);
    let half = [0.6f32, 0.35, 0.02];
    let height = 0.75f32;
    let axes = [
        rotate_z([1.0, 0.0, 0.0], yaw),
        rotate_z([0.0, 1.0, 0.0], yaw),
        [0.0, 0.0, 1.0],
    ];
    let mut prims = vec![Primitive {
        shape: Shape::Box {
            center: [center[0], center[1], height - half[2]],
            axes,
            half,
        },
        owner: Owner::Scene,
        material: wood,
    }];
    for (sx, sy) in [(-1.0f32, -1.0f32), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
        let offset = rotate_z([sx * (half[0] - 0.05), sy * (half[1] - 0.05), 0.0], yaw);
        let foot = [center[0] + offset[0], center[1] + offset[1], 0.0];
        prims.push(Primitive {
            shape: Shape::Cylinder {
                a: foot,
                b: [foot[0], foot[1], height - 2.0 * half[2]],
                radius: 0.025,
            },
            owner: Owner::Scene,
            material: metal,
        });
    }
    prims
}

impl RobotArm {
    fn primitives_at(&self, t: f32) -> Vec<Primitive> {
        let owner = Owner::Scene;
        let base_top = [self.base[0], self.base[1], 0.75];
        let mut prims = vec![Primitive {
            shape: Shape::Cylinder {
                a: [self.base[0], self.base[1], 0.0],
                b: base_top,
                radius: 0.16,
            },
            owner,
            material: self.joint_material,
        }];
        // Slow joint motion (periods of 5–9 s): swivel, shoulder, elbow.
        let swivel = self.yaw + 0.5 * (0.7 * t + self.phase[0]).sin();
        let shoulder = 0.6 + 0.35 * (0.9 * t + self.phase[1]).sin();
        let elbow = 1.2 + 0.4 * (1.1 * t + self.phase[2]).sin();
        let forward = rotate_z([1.0, 0.0, 0.0], swivel);
        let dir1 = normalize2(forward, shoulder);
        let dir2 = normalize2(forward, shoulder - elbow);
        let shoulder_p = [base_top[0], base_top[1], base_top[2] + 0.12];
        let elbow_p = add(shoulder_p, scale(dir1, 0.55));
        let wrist_p = add(elbow_p, scale(dir2, 0.5));
        let tool_p = add(wrist_p, scale(dir2, 0.12));
        prims.push(Primitive {
            shape: Shape::Cylinder {
                a: base_top,
                b: shoulder_p,
                radius: 0.11,
            },
            owner,
            material: self.material,
        });
        prims.push(Primitive {
            shape: Shape::Cylinder {
                a: shoulder_p,
                b: elbow_p,
                radius: 0.07,
            },
            owner,
            material: self.material,
        });
        prims.push(Primitive {
            shape: Shape::Cylinder {
                a: elbow_p,
                b: wrist_p,
                radius: 0.055,
            },
            owner,
            material: self.material,
        });
        for (p, r) in [(shoulder_p, 0.1f32), (elbow_p, 0.085), (wrist_p, 0.065)] {
            let axis = frame_from_axis(rotate_z([0.0, 1.0, 0.0], swivel));
            prims.push(Primitive {
                shape: Shape::Ellipsoid {
                    center: p,
                    axes: axis,
                    radii: [r, r, r],
                },
                owner,
                material: self.joint_material,
            });
        }
        prims.push(Primitive {
            shape: Shape::Cylinder {
                a: wrist_p,
                b: tool_p,
                radius: 0.035,
            },
            owner,
            material: self.joint_material,
        });
        prims
    }
}

/// Unit direction `forward` tilted up by `elevation` radians.
fn normalize2(forward: V3, elevation: f32) -> V3 {
    let (s, c) = elevation.sin_cos();
    [forward[0] * c, forward[1] * c, s]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn robot_cell_scene_has_its_objects_and_the_arm_moves() {
        let config = StaticSceneConfig {
            table: true,
            robot_arm: true,
            boxes: 2,
            ..StaticSceneConfig::default()
        };
        let scene = StaticScene::new(&config, 3);
        let groups = scene.groups_at(0.0);
        assert_eq!(groups.len(), 4, "table, 2 boxes, robot");
        assert_eq!(scene.obstacles().len(), 4);
        let later = scene.groups_at(1.0);
        assert_ne!(groups[3], later[3], "the arm moves");
        assert_eq!(groups[..3], later[..3], "the rest stays");
        for g in &groups {
            for p in g {
                let (lo, _) = p.shape.aabb();
                assert!(lo[2] >= -1e-4, "nothing below the floor: {p:?}");
            }
        }
    }
}
