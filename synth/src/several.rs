//! Scenes of several ropes: two of one colour crossing, one dragged over
//! the other or pulled out from under it, and three of different colours
//! under a passing box. Each rope is simulated beside the others (they lie
//! on each other, [`Rope::step_among`]) and has its own ground truth, with
//! what hides it: a box, or another rope in front.

use alloc::string::String;
use alloc::vec::Vec;

use upetrack::math::Vec3;
use upetrack::rng::SplitMix64;
use upetrack::{CameraIntrinsics, HsvRange};

use crate::events::{BoxPath, MovingBox, Pull};
use crate::plan::{bowed, laid, Grasp, Laid, Plan, BLUE, GREEN, RED};
use crate::render::{
    hidden_by_boxes, hidden_by_ropes, render_ropes, rope_hsv, CameraPose, OccluderBox,
    RenderSettings, RopeLook,
};
use crate::rope::{Obstacle, Rope, RopeSettings};
use crate::scenario::SETTLING_FRAMES;
use crate::several_drawn::{drawn_plan, DRAWN_STREAM};
use crate::MAX_FRAMES;

/// Which scene of several ropes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SeveralKind {
    /// Two ropes of one colour in an X; the upper one is dragged sideways
    /// across the lower, so the crossing slides along it.
    Crossing,
    /// Two ropes of one colour in an X; the lower one is pulled out along
    /// its own axis from under the upper.
    FromUnder,
    /// Three ropes (red, blue, green), the green lying across the other
    /// two; a box passes over the middle while each is dragged at one end.
    ThreeColours,
    /// Two ropes of one colour side by side; one is dragged out of the
    /// image and back beside the other.
    LeavesView,
}

impl SeveralKind {
    /// Every scene of several ropes.
    pub const ALL: [Self; 4] = [
        Self::Crossing,
        Self::FromUnder,
        Self::ThreeColours,
        Self::LeavesView,
    ];

    /// Its command-line name.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Crossing => "two-ropes-crossing",
            Self::FromUnder => "rope-from-under",
            Self::ThreeColours => "three-ropes",
            Self::LeavesView => "rope-leaves-view",
        }
    }

    /// The scene called `name`.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// One sentence on what it shows.
    pub fn description(&self) -> &'static str {
        match self {
            Self::Crossing => "two blue ropes in an X; from 30 % of the frames on the upper one is dragged 14 cm sideways across the lower, the crossing sliding along it",
            Self::FromUnder => "two blue ropes in an X; from 30 % of the frames on the lower one is pulled 14 cm along its own axis, its far end passing out from under the upper",
            Self::ThreeColours => "a red, a blue and a green rope, the green lying across the other two; a box passes 8 cm over the middle while each is dragged 6 cm at one end",
            Self::LeavesView => "two blue ropes side by side; from 15 % of the frames on one is dragged 34 cm sideways out of the image, and from 55 % back beside the other",
        }
    }

    /// Number of ropes.
    pub fn rope_count(&self) -> usize {
        match self {
            Self::Crossing | Self::FromUnder | Self::LeavesView => 2,
            Self::ThreeColours => 3,
        }
    }
}

/// One rope's ground truth in a frame.
#[derive(Debug, Clone, PartialEq)]
pub struct RopeTruth {
    /// Centre line, ordered, metres, colour camera frame.
    pub points: Vec<Vec3>,
    /// For each point: hidden by a box or by another rope in front.
    pub occluded: Vec<bool>,
}

/// One rendered frame of several ropes.
#[derive(Debug, Clone)]
pub struct SeveralFrame {
    /// Frame index.
    pub index: usize,
    /// RGB8.
    pub rgb: Vec<u8>,
    /// Depth, millimetres.
    pub depth: Vec<u16>,
    /// Each rope's ground truth, in the scene's order.
    pub ropes: Vec<RopeTruth>,
    /// Where the camera was.
    pub camera_pose: CameraPose,
}

/// A scene of several ropes being recorded.
#[derive(Debug, Clone)]
pub struct SeveralRopes {
    /// Its command-line name (with `-without-<k>` when a rope was left out).
    pub name: String,
    /// Which described scene (`None` for a drawn one).
    pub kind: Option<SeveralKind>,
    /// Frames to record.
    pub frames: usize,
    /// Rendering settings (the camera; the rope colours are the ropes').
    pub render: RenderSettings,
    /// The ropes simulated.
    pub ropes: Vec<Rope>,
    /// Each rope's albedo.
    pub colors: Vec<[f64; 3]>,
    /// Each rope's name (its colour, and a letter where two share one).
    pub names: Vec<String>,
    rng: SplitMix64,
    next: usize,
    /// Grasps: the rope, the grasp and its particle's settled position.
    pulls: Vec<(usize, Pull, Vec3)>,
    boxes: Vec<MovingBox>,
}

/// Which of a scene's ropes are made.
#[derive(Debug, Clone, Copy)]
enum Keep {
    /// All but this one.
    AllBut(usize),
    /// This one alone.
    Only(usize),
}

impl SeveralRopes {
    /// Sets up `kind` with `frames` frames (at least 1) and a seed; the
    /// ropes are settled on the table and on each other first.
    pub fn new(kind: SeveralKind, frames: usize, seed: u64) -> Self {
        Self::build(kind, frames, seed, None)
    }

    /// The same scene with rope `removed` left out (simulated and drawn
    /// without it): the single-rope figure a scene of several is judged
    /// against. `None` when there is no such rope.
    pub fn without(kind: SeveralKind, frames: usize, seed: u64, removed: usize) -> Option<Self> {
        (removed < kind.rope_count())
            .then(|| Self::build(kind, frames, seed, Some(Keep::AllBut(removed))))
    }

    /// The same scene with rope `kept` alone (simulated and drawn without
    /// the others). `None` when there is no such rope.
    pub fn only(kind: SeveralKind, frames: usize, seed: u64, kept: usize) -> Option<Self> {
        (kept < kind.rope_count()).then(|| Self::build(kind, frames, seed, Some(Keep::Only(kept))))
    }

    fn build(kind: SeveralKind, frames: usize, seed: u64, chosen: Option<Keep>) -> Self {
        let frames = frames.clamp(1, MAX_FRAMES);
        let mut rng = SplitMix64::new(seed);
        // Small seeded variation of the layout: a shift of the whole scene.
        let shift = Vec3::new(rng.range(-0.01, 0.01), rng.range(-0.01, 0.01), 0.0);
        let plan = described(kind, frames, shift);
        let mut name = String::from(kind.name());
        match chosen {
            None => {}
            Some(Keep::AllBut(k)) => name.push_str(&alloc::format!("-without-{k}")),
            Some(Keep::Only(k)) => name.push_str(&alloc::format!("-only-{k}")),
        }
        Self::make(plan, name, Some(kind), frames, rng, chosen)
    }

    /// A scene of several ropes drawn whole from `seed` (two or three ropes, of one colour or of several,
    /// crossing, dragged or pulled, a box passing or not).
    pub fn random(seed: u64, frames: usize) -> Self {
        let frames = frames.clamp(1, MAX_FRAMES);
        let mut rng = SplitMix64::new(seed ^ DRAWN_STREAM);
        let plan = drawn_plan(&mut rng, frames);
        let name = alloc::format!("several-random-{seed}");
        Self::make(plan, name, None, frames, rng, None)
    }

    fn make(
        plan: Plan,
        name: String,
        kind: Option<SeveralKind>,
        frames: usize,
        rng: SplitMix64,
        chosen: Option<Keep>,
    ) -> Self {
        let at = |f: f64| ((frames as f64 * f) as usize).min(frames - 1);
        let Plan {
            laid,
            grasps: pulls,
            boxes,
        } = plan;

        let keep: Vec<usize> = (0..laid.len())
            .filter(|&k| match chosen {
                None => true,
                Some(Keep::AllBut(r)) => k != r,
                Some(Keep::Only(o)) => k == o,
            })
            .collect();
        let mut ropes: Vec<Rope> = Vec::new();
        for &k in &keep {
            let settings = RopeSettings {
                length: laid[k].length,
                thickness: laid[k].thickness,
                // Particles about 1 cm apart.
                particles: (libm::round(laid[k].length / 0.01) as usize + 1).max(3),
                ..RopeSettings::default()
            };
            let mut rope = Rope::laid_along(&laid[k].shape, settings);
            // Over the ropes it lies on: lifted onto them, then settled.
            for &j in laid[k].over.iter().filter(|j| keep.contains(*j)) {
                let under = keep.iter().position(|&x| x == j).map(|i| &ropes[i]);
                if let Some(under) = under {
                    lift_over(&mut rope, under);
                }
            }
            ropes.push(rope);
        }
        for _ in 0..SETTLING_FRAMES {
            step_all(&mut ropes);
        }
        let pulls = pulls
            .into_iter()
            .filter_map(
                |Grasp {
                     rope: k,
                     particle,
                     offset,
                     start,
                     end,
                     from,
                 }| {
                    let rope = keep.iter().position(|&x| x == k)?;
                    let particle = particle.min(ropes[rope].x.len() - 1);
                    let pull = Pull {
                        particle,
                        start: at(start),
                        end: at(end),
                        offset,
                        circular: false,
                    };
                    Some((rope, pull, ropes[rope].x[particle] + from))
                },
            )
            .collect();
        Self {
            name,
            kind,
            frames,
            render: RenderSettings::default(),
            colors: keep.iter().map(|&k| laid[k].color).collect(),
            names: keep.iter().map(|&k| laid[k].name.clone()).collect(),
            ropes,
            rng,
            next: 0,
            pulls,
            boxes,
        }
    }

    /// HSV thresholds that fit rope `k`'s colour.
    pub fn hsv(&self, k: usize) -> HsvRange {
        rope_hsv(self.colors.get(k).copied().unwrap_or(BLUE))
    }

    /// The camera.
    pub fn camera(&self) -> CameraIntrinsics {
        self.render.camera
    }

    /// A pixel on rope `k` now, as a user would click to say which rope it
    /// is: of the middle half of it, the point farthest from every other
    /// rope (never a crossing); `None` when it is not in view.
    pub fn hint(&self, k: usize) -> Option<upetrack::math::Vec2> {
        let rope = self.ropes.get(k)?;
        let n = rope.x.len();
        let clearance = |p: &Vec3| {
            self.ropes
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != k)
                .flat_map(|(_, o)| o.x.iter())
                .map(|q| libm::hypot(p.x - q.x, p.y - q.y))
                .fold(f64::INFINITY, f64::min)
        };
        let best = rope.x[n / 4..(3 * n / 4).max(n / 4 + 1).min(n)]
            .iter()
            .max_by(|a, b| clearance(a).total_cmp(&clearance(b)))?;
        let q = self
            .render
            .camera
            .project(&self.render.pose().world_to_camera(best))?;
        let cam = &self.render.camera;
        (q.x >= 0.0 && q.y >= 0.0 && q.x < cam.width as f64 && q.y < cam.height as f64).then_some(q)
    }

    /// Simulates and renders the next frame, or `None` after the last.
    pub fn next_frame(&mut self) -> Option<SeveralFrame> {
        if self.next >= self.frames {
            return None;
        }
        let f = self.next;
        self.next += 1;
        if f > 0 {
            for (rope, pull, origin) in &self.pulls {
                if let Some(target) = pull.target(*origin, f) {
                    self.ropes[*rope].grasp(pull.particle, target);
                }
            }
            step_all(&mut self.ropes);
        }
        let boxes: Vec<OccluderBox> = self
            .boxes
            .iter()
            .filter(|b| (b.first..=b.last).contains(&f))
            .map(|b| b.at(f, &[], &[]))
            .collect();
        let looks: Vec<RopeLook<'_>> = self
            .ropes
            .iter()
            .zip(&self.colors)
            .map(|(r, c)| RopeLook {
                particles: &r.x,
                radius: r.radius(),
                color: *c,
                second_color: None,
            })
            .collect();
        let rendered = render_ropes(&self.render, &looks, &boxes, &mut self.rng);
        let pose = self.render.pose();
        let ropes = self
            .ropes
            .iter()
            .enumerate()
            .map(|(k, rope)| {
                let others: Vec<RopeLook<'_>> = looks
                    .iter()
                    .enumerate()
                    .filter(|(j, _)| *j != k)
                    .map(|(_, l)| *l)
                    .collect();
                RopeTruth {
                    points: rope.x.iter().map(|p| pose.world_to_camera(p)).collect(),
                    occluded: rope
                        .x
                        .iter()
                        .map(|p| {
                            hidden_by_boxes(&self.render, p, rope.radius(), &boxes)
                                || hidden_by_ropes(&self.render, p, rope.radius(), &others)
                        })
                        .collect(),
                }
            })
            .collect();
        Some(SeveralFrame {
            index: f,
            rgb: rendered.rgb,
            depth: rendered.depth,
            ropes,
            camera_pose: pose,
        })
    }

    /// Frames not yet rendered.
    pub fn remaining(&self) -> usize {
        self.frames - self.next
    }
}

/// The plan of a described scene of `frames` frames, shifted by `shift`.
fn described(kind: SeveralKind, frames: usize, shift: Vec3) -> Plan {
    let at = |f: f64| ((frames as f64 * f) as usize).min(frames - 1);
    let line = |a: [f64; 2], b: [f64; 2], bow: f64| bowed(a, b, bow, shift);
    let (laid, grasps, boxes): (Vec<Laid>, Vec<Grasp>, Vec<MovingBox>) = match kind {
        SeveralKind::Crossing => (
            alloc::vec![
                laid(line([-0.21, 0.0], [0.21, 0.02], 0.03), BLUE, "blue-a", &[]),
                laid(
                    line([-0.07, -0.2], [-0.07, 0.2], -0.02),
                    BLUE,
                    "blue-b",
                    &[0]
                ),
            ],
            // Both ends of the upper rope, 14 cm along x.
            alloc::vec![
                Grasp {
                    rope: 1,
                    particle: 0,
                    offset: Vec3::new(0.14, 0.0, 0.0),
                    start: 0.3,
                    end: 0.85,
                    from: Vec3::zeros(),
                },
                Grasp {
                    rope: 1,
                    particle: usize::MAX,
                    offset: Vec3::new(0.14, 0.0, 0.0),
                    start: 0.3,
                    end: 0.85,
                    from: Vec3::zeros(),
                },
            ],
            Vec::new(),
        ),
        SeveralKind::FromUnder => (
            alloc::vec![
                laid(line([-0.11, 0.0], [0.26, 0.0], 0.03), BLUE, "blue-a", &[]),
                laid(line([0.14, -0.2], [0.14, 0.2], 0.02), BLUE, "blue-b", &[0]),
            ],
            // The lower rope's near end, 14 cm along its own axis: its
            // far end passes under the upper rope and out.
            alloc::vec![Grasp {
                rope: 0,
                particle: 0,
                offset: Vec3::new(-0.14, 0.0, 0.0),
                start: 0.3,
                end: 0.85,
                from: Vec3::zeros(),
            }],
            Vec::new(),
        ),
        SeveralKind::ThreeColours => (
            alloc::vec![
                laid(line([-0.2, -0.09], [0.2, -0.07], 0.02), RED, "red", &[]),
                laid(line([-0.2, 0.04], [0.2, 0.05], -0.02), BLUE, "blue", &[]),
                laid(
                    line([-0.12, -0.19], [0.1, 0.18], 0.02),
                    GREEN,
                    "green",
                    &[0, 1]
                ),
            ],
            alloc::vec![
                Grasp {
                    rope: 0,
                    particle: usize::MAX,
                    offset: Vec3::new(0.0, -0.06, 0.0),
                    start: 0.35,
                    end: 0.85,
                    from: Vec3::zeros(),
                },
                Grasp {
                    rope: 1,
                    particle: usize::MAX,
                    offset: Vec3::new(0.0, 0.06, 0.0),
                    start: 0.35,
                    end: 0.85,
                    from: Vec3::zeros(),
                },
                Grasp {
                    rope: 2,
                    particle: usize::MAX,
                    offset: Vec3::new(0.06, 0.0, 0.0),
                    start: 0.35,
                    end: 0.85,
                    from: Vec3::zeros(),
                },
            ],
            alloc::vec![MovingBox {
                first: at(0.3),
                last: at(0.7),
                shape: OccluderBox {
                    min: Vec3::new(-0.24, -0.04, 0.08) + shift,
                    max: Vec3::new(-0.17, 0.04, 0.12) + shift,
                    color: None,
                },
                path: BoxPath::Linear {
                    travel: Vec3::new(0.36, 0.0, 0.0),
                    bob: 0.0,
                    dwell: true,
                },
            }],
        ),
        SeveralKind::LeavesView => {
            let out = Vec3::new(0.34, 0.0, 0.0);
            // Both ends of the second rope, out and back.
            let grasps = [0, usize::MAX].into_iter().flat_map(|particle| {
                [
                    Grasp {
                        rope: 1,
                        particle,
                        offset: out,
                        start: 0.15,
                        end: 0.4,
                        from: Vec3::zeros(),
                    },
                    Grasp {
                        rope: 1,
                        particle,
                        offset: -out,
                        start: 0.55,
                        end: 0.8,
                        from: out,
                    },
                ]
            });
            (
                alloc::vec![
                    laid(line([-0.06, -0.2], [-0.06, 0.2], 0.03), BLUE, "blue-a", &[]),
                    laid(line([0.1, -0.2], [0.1, 0.2], -0.03), BLUE, "blue-b", &[]),
                ],
                grasps.collect(),
                Vec::new(),
            )
        }
    };
    Plan {
        laid,
        grasps,
        boxes,
    }
}

/// One frame of physics for every rope, each beside the others as they
/// stand (in order, so later ropes see the earlier ones' new positions).
fn step_all(ropes: &mut [Rope]) {
    for k in 0..ropes.len() {
        let (before, rest) = ropes.split_at_mut(k);
        let Some((rope, after)) = rest.split_first_mut() else {
            continue;
        };
        let others: Vec<Obstacle<'_>> = before
            .iter()
            .chain(after.iter())
            .map(|o| Obstacle {
                particles: &o.x,
                radius: o.radius(),
            })
            .collect();
        rope.step_among(1.0 / crate::SIMULATED_FPS, &others);
    }
}

/// Raises the particles of `rope` that lie across `under` onto it, with a
/// ramp of a few particles either side, so that settling lays it over.
fn lift_over(rope: &mut Rope, under: &Rope) {
    let reach = 2.0 * (rope.radius() + under.radius());
    let top = 2.0 * under.radius() + rope.radius();
    let near: Vec<f64> = rope
        .x
        .iter()
        .map(|p| {
            under
                .x
                .iter()
                .map(|q| libm::hypot(p.x - q.x, p.y - q.y))
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    let (radius, half) = (rope.radius(), rope.settings.thickness / 2.0);
    for (p, d) in rope.x.iter_mut().zip(near) {
        // Full height within reach of the lower rope, falling off over
        // three reaches.
        let x = ((d - reach) / (3.0 * reach)).clamp(0.0, 1.0);
        p.z = p.z.max(half + (top - radius) * (1.0 - x));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_upper_rope_lies_on_the_lower_and_each_has_its_ground_truth() {
        let mut scene = SeveralRopes::new(SeveralKind::Crossing, 3, 1);
        let frame = scene.next_frame().expect("a frame");
        assert_eq!(frame.ropes.len(), 2);
        // The upper rope rests on the lower: at the crossing it is about a
        // diameter above the table's rope, nowhere inside it.
        let (lower, upper) = (&scene.ropes[0], &scene.ropes[1]);
        let highest = upper.x.iter().map(|p| p.z).fold(0.0, f64::max);
        assert!(
            (highest - (2.0 * lower.radius() + upper.radius())).abs() < 0.003,
            "{highest}"
        );
        for p in &upper.x {
            for q in &lower.x {
                assert!((p - q).norm() > 0.9 * (lower.radius() + upper.radius()));
            }
        }
        // Where it passes over, the lower rope is hidden from the camera.
        assert!(frame.ropes[0].occluded.iter().any(|&o| o));
        assert!(frame.ropes[1].occluded.iter().all(|&o| !o));
    }

    #[test]
    fn a_scene_without_a_rope_keeps_the_others_and_is_deterministic() {
        let mut a = SeveralRopes::without(SeveralKind::ThreeColours, 2, 5, 1).expect("rope 1");
        let mut b = SeveralRopes::without(SeveralKind::ThreeColours, 2, 5, 1).expect("rope 1");
        assert_eq!(a.names, ["red", "green"]);
        let (fa, fb) = (
            a.next_frame().expect("frame"),
            b.next_frame().expect("frame"),
        );
        assert_eq!(fa.rgb, fb.rgb);
        assert_eq!(fa.depth, fb.depth);
        assert!(SeveralRopes::without(SeveralKind::ThreeColours, 2, 5, 3).is_none());
        assert_eq!(
            SeveralKind::parse("rope-from-under"),
            Some(SeveralKind::FromUnder)
        );
    }
}
