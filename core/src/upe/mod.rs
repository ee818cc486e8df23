//! UPETrack's own per-frame step, one module per stage in the paper's order:
//! [`registration`] (GMM-EM of the visible nodes, after the shared
//! [`crate::visibility`] test of Fig. 3),
//! Eq. 1-5), [`mod@shared_motion`] (the rigid motion the visible rope shares,
//! which the hidden nodes follow), [`occlusion`] (Unidirectional Position Estimation of the hidden
//! nodes, Eq. 6-11) and [`resampling`] (Eq. 12-15). [`UpeTrackParams`] holds
//! the step's parameters; [`UpeTrackStep`] runs the stages.

pub mod bends;
pub mod emerging;
pub mod explain;
pub mod free_space;
pub mod length;
pub mod occlusion;
pub mod registration;
pub mod resampling;
pub mod shared_motion;
pub mod slide;

use crate::perception::table::{fit_table, Plane};
use emerging::{follow_emerged_ends, follow_rope_past_ends, lies_on, EmergedReport, InView};
use free_space::{clear_free_space, FreeSpaceReport};
use length::{
    conserve_end_lengths, conserve_middle_lengths, extend_short_ends,
    resample_with_end_runs_at_rest, ExtensionReport, LengthReport, OpenEnds,
};
use occlusion::{estimate_hidden_with_sweeps, HiddenMotion, UpeCoefficients, UpeReport};
use registration::{register_observed, EmReport, EmSettings, MAX_EM_ITERATIONS};
use resampling::resample;
use shared_motion::shared_motion;

use alloc::vec::Vec;

use crate::math::Vec3;
use crate::step::{Algorithm, StepInput, StepOutput, TrackingStep};
use crate::validation::{below_one, check, unit, ParamsError};

/// Default [`UpeTrackParams::rest_speed_m_per_s`]: 6 cm/s, 2 mm a frame at
/// the D435i's 30 frames/s, about twice the frame-to-frame jitter across
/// the rope of a visible node of a resting rope (0.9 mm median on
/// static-s).
pub const DEFAULT_REST_SPEED: f64 = 0.06;
/// Shortest time over which the rest speed is judged, seconds (one frame
/// at the D435i's default 30 frames/s): at a faster rate a frame's move is
/// mostly the images' jitter, which does not shrink with the interval, so
/// the move a resting rope may show in one frame stays the rest speed's
/// over this time. Chosen on the tuning range filmed at 60 frames/s
/// (`docs/algorithm-notes.md`).
pub const MIN_REST_INTERVAL_S: f64 = 1.0 / 30.0;
/// Largest [`UpeTrackParams::rest_speed_m_per_s`] accepted, metres per
/// second (well beyond any rope a camera follows).
pub const MAX_REST_SPEED: f64 = 30.0;

/// UPETrack's parameters for the registration and the occlusion estimate
/// (the visibility test and `M` are shared by every algorithm and sit in
/// [`crate::params::Params`]).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default))]
pub struct UpeTrackParams {
    /// Distance attenuation factor of the local displacement term (`gamma`, Eq. 6). Paper: 0.8.
    pub displacement_decay: f64,
    /// Historical curvature retention (`a`, Eq. 10). Paper: 0.6.
    pub curvature_retention: f64,
    /// Bending resistance of the proximal linear constraint (`b`, Eq. 8). Paper: 0.8.
    pub bending_resistance: f64,
    /// Weight of the displacement estimate (`alpha`, Eq. 11). Paper: 0.75.
    pub displacement_weight: f64,
    /// `alpha` for a hidden run of two or more nodes that includes an end of
    /// the rope (`occlusion::MIN_END_RUN`). Default 1
    /// (the displacement term alone: a hidden tip moves with its visible
    /// neighbours and keeps its shape); `displacement_weight` gives the
    /// paper's rule. See `docs/algorithm-notes.md`.
    pub end_displacement_weight: f64,
    /// The displacement estimate of a hidden node: `slide_ends` (default:
    /// a run that reaches an end of the rope slides along its previous
    /// curve with the rope and moves across it with its anchor; middle
    /// runs use Eq. 6-7), `paper` (Eq. 6-7 everywhere) or `slide` (every run).
    pub hidden_motion: HiddenMotion,
    /// The rope does not stretch: a hidden run at an end of the rope is no
    /// longer than the arc length the rest of the rope leaves of its known
    /// length, and the hidden runs between visible stretches give up what
    /// the rope has over that length (their bends tighten; pulled from one
    /// side, a run straightens from that side). Default true.
    pub conserve_length: bool,
    /// Move hidden runs out of free space: where the images show nothing
    /// that could hide them (`perception::evidence`). Default true.
    pub free_space: bool,
    /// Take only the known nodes' displacement across the rope as `D_k` of
    /// Eq. 6 (its component along the previous tangent removed): a node's
    /// slide along the rope under EM is its parameterisation, not the
    /// rope's motion. Default true; false is the paper's `D_k`.
    pub across_rope_displacement: bool,
    /// Resample (Eq. 12-15) along the centripetal Catmull-Rom curve through
    /// the nodes rather than along their polyline, so that resampling does
    /// not cut a bend's corners every frame. Default true; false is the
    /// paper's polyline.
    pub smooth_resampling: bool,
    /// Speed of a hidden node's known neighbours below which its run is
    /// taken to rest, metres per second (a move per frame at the tracker's
    /// frame rate, `StepInput::frame_interval`, judged over at least
    /// [`MIN_REST_INTERVAL_S`]): below it `alpha` of
    /// Eq. 11 rises from `displacement_weight` to 1 at rest, with the
    /// square of the speed (`occlusion::resting_weight`). Default
    /// [`DEFAULT_REST_SPEED`]; 0 is the paper's fixed `alpha`. (Parameter
    /// files before this field gave `rest_speed` in metres per frame; it
    /// is refused with a message rather than read in the new unit.)
    pub rest_speed_m_per_s: f64,
    /// Keep only the across-rope part of EM's move of a visible node next
    /// to a hidden run (an anchor of Eq. 6-11): at an occlusion's edge the
    /// cloud lies on one side of the node only, and the GMM pulls it away
    /// from the edge along the rope every frame (about a third of a node
    /// spacing), which is no motion of the rope. Default true; false is the
    /// paper's EM.
    pub anchor_across_only: bool,
    /// Nodes the relative visibility test hid although they have `V_lim`
    /// points within `r_vis` (`StepInput::partly_seen`) take part in EM's
    /// E-step as fixed components: their points are explained by them
    /// instead of pulling the visible node next to them into the hidden
    /// run. Default true; false is the paper's EM (hidden nodes take no
    /// part).
    pub hidden_nodes_absorb: bool,
    /// Give a rope found shorter than its rest length the difference back
    /// along its ends' tangents, as far as the images show rope there (or
    /// the rope leaves the image; `length::extend_short_ends`): EM draws an
    /// end node in towards the middle of the points it sees. Default true;
    /// false is the paper's rule (nothing keeps the length).
    pub extend_short_ends: bool,
    /// Let [`UpeTrackParams::extend_short_ends`] also go on where something
    /// hides the rope at the pixel (depth nearer the camera, a declared
    /// rectangle; `Evidence::hides_rope_at`): a visible end that meets an
    /// occluder goes on under it, as a rope held in a gripper's jaws does.
    /// Default true.
    pub extend_under_occluders: bool,
    /// Keep each hidden run at an end of the rope at the rest spacing
    /// through resampling (`length::resample_with_end_runs_at_rest`), so
    /// length the rope lost where nothing shows it is not taken from every
    /// hidden run in turn. Default true; false is the paper's resampling
    /// of the whole rope.
    pub keep_end_run_spacing: bool,
    /// Move the hidden nodes with the rigid motion most visible nodes
    /// share (`shared_motion`: a camera on an arm or in a hand, the whole
    /// rope carried) before Eq. 6-11 and the rules for a resting rope judge
    /// what is left of the visible nodes' motion. Default false: on the
    /// randomised tuning range it helps where the camera moves on an arm
    /// and hurts where the rope itself moves in front of a still camera
    /// (`docs/algorithm-notes.md`); set it when the camera moves. False
    /// is the paper's step.
    pub follow_shared_motion: bool,
    /// Lay a hidden end onto rope that came out from under its occluder
    /// (`emerging::follow_emerged_ends`): rope in view that no node
    /// explains, next to hidden space and within the hidden run's reach,
    /// is where a hidden end pulled out went; and let a rope found
    /// shorter than its rest length go on past an end along rope in view
    /// no node explains, within what it lacks
    /// (`emerging::follow_rope_past_ends`: EM leaves a fast-pulled end
    /// behind). Default true; false is the paper's step (hidden nodes
    /// follow their anchors only).
    pub follow_emerged_ends: bool,
    /// A node under another stretch of the rope where the rope crosses
    /// itself is hidden (`visibility::under_other_strand`): the images
    /// show the stretch on top there, whose points are not the node's; it
    /// explains its points as a partly seen node and moves with its
    /// neighbours. Which stretch is on top is read from the depth beside
    /// the crossing. Default true; false is the paper's visibility.
    pub hidden_under_crossings: bool,
    /// Report each visible node on its bend's arc rather than where EM
    /// left it, the centroid of the rope points it explains, which lies
    /// inside the bend (`bends::onto_arcs`). Only the reported nodes move:
    /// the next frame starts from EM's. Default true; false is the paper's
    /// nodes.
    pub report_on_arcs: bool,
    /// Report each end node in view where the rope's tip is seen
    /// (`length::seen_tip`) rather than where EM left it, inside the tip
    /// (its Gaussian has points on one side only). Only the reported
    /// nodes move: the next frame starts from EM's. Default true; false is
    /// the paper's nodes.
    pub report_seen_tips: bool,
    /// Weight of the uniform outlier component (`w`, Eq. 3). Default 0.1.
    pub outlier_weight: f64,
    /// EM stops when no node moves more than this in an iteration, metres. Default 0.1 mm.
    pub em_tolerance: f64,
    /// Most EM iterations per frame. Default 10 (30 costs three times as much and was no more accurate on the synthetic scenarios).
    pub em_max_iterations: u32,
    /// Floor of the GMM variance (`sigma^2`), square metres. Default (1 mm)^2.
    pub min_variance: f64,
}

impl Default for UpeTrackParams {
    /// The paper's `gamma = 0.8`, `a = 0.6`, `b = 0.8`, `alpha = 0.75`, and
    /// this project's choices where the paper is silent.
    fn default() -> Self {
        Self {
            displacement_decay: 0.8,
            curvature_retention: 0.6,
            bending_resistance: 0.8,
            displacement_weight: 0.75,
            end_displacement_weight: 1.0,
            hidden_motion: HiddenMotion::SlideEnds,
            conserve_length: true,
            free_space: true,
            across_rope_displacement: true,
            smooth_resampling: true,
            rest_speed_m_per_s: DEFAULT_REST_SPEED,
            anchor_across_only: true,
            hidden_nodes_absorb: true,
            extend_short_ends: true,
            extend_under_occluders: true,
            keep_end_run_spacing: true,
            follow_shared_motion: false,
            follow_emerged_ends: true,
            hidden_under_crossings: true,
            report_on_arcs: true,
            report_seen_tips: true,
            outlier_weight: 0.1,
            em_tolerance: 1e-4,
            em_max_iterations: 10,
            min_variance: 1e-6,
        }
    }
}

impl UpeTrackParams {
    /// Checks every field against its documented range.
    pub fn validate(&self) -> Result<(), ParamsError> {
        unit("displacement_decay", self.displacement_decay)?;
        unit("curvature_retention", self.curvature_retention)?;
        unit("displacement_weight", self.displacement_weight)?;
        unit("end_displacement_weight", self.end_displacement_weight)?;
        let b = self.bending_resistance;
        check(
            "bending_resistance",
            b,
            (0.0..=2.0).contains(&b),
            "in [0, 2]",
        )?;
        let w = self.outlier_weight;
        below_one("outlier_weight", w)?;
        let t = self.em_tolerance;
        check("em_tolerance", t, t > 0.0 && t <= 1.0, "in (0, 1] metres")?;
        let it = self.em_max_iterations;
        check(
            "em_max_iterations",
            it as f64,
            (1..=MAX_EM_ITERATIONS).contains(&it),
            "an integer in 1..=1000",
        )?;
        let r = self.rest_speed_m_per_s;
        check(
            "rest_speed_m_per_s",
            r,
            (0.0..=MAX_REST_SPEED).contains(&r),
            "in [0, 30] metres per second",
        )?;
        let s = self.min_variance;
        check(
            "min_variance",
            s,
            s > 0.0 && s <= 1.0,
            "in (0, 1] square metres",
        )
    }

    /// The UPE coefficients for frames `frame_interval` seconds apart.
    pub fn upe(&self, frame_interval: f64) -> UpeCoefficients {
        UpeCoefficients {
            displacement_decay: self.displacement_decay,
            curvature_retention: self.curvature_retention,
            bending_resistance: self.bending_resistance,
            displacement_weight: self.displacement_weight,
            end_displacement_weight: self.end_displacement_weight,
            hidden_motion: self.hidden_motion,
            across_rope_displacement: self.across_rope_displacement,
            rest_move: self.rest_speed_m_per_s * frame_interval.max(MIN_REST_INTERVAL_S),
        }
    }

    /// The EM settings.
    pub fn em(&self) -> EmSettings {
        EmSettings {
            outlier_weight: self.outlier_weight,
            tolerance: self.em_tolerance,
            max_iterations: self.em_max_iterations,
            min_variance: self.min_variance,
        }
    }
}

/// What UPETrack's step did: the registration and the occlusion estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct UpeTrackReport {
    /// The registration of the visible nodes.
    pub em: EmReport,
    /// How the hidden nodes were placed.
    pub upe: UpeReport,
    /// What length conservation did to hidden ends.
    pub length: LengthReport,
    /// What the free-space check moved.
    pub free_space: FreeSpaceReport,
    /// What the ends were given back of the rope's length.
    pub extension: ExtensionReport,
    /// Hidden ends laid onto rope that came out from under an occluder.
    pub emerged: EmergedReport,
}

/// UPETrack's step: GMM-EM of the visible nodes, UPE of the hidden ones,
/// uniform resampling. It keeps nothing between frames.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct UpeTrackStep;

impl TrackingStep for UpeTrackStep {
    type Settings = UpeTrackParams;
    type Report = UpeTrackReport;
    const ALGORITHM: Algorithm = Algorithm::Upetrack;

    fn start(&mut self, _nodes: &[Vec3]) {}

    fn step(
        &mut self,
        input: &StepInput<'_>,
        settings: &UpeTrackParams,
    ) -> StepOutput<UpeTrackReport> {
        run_step(input, settings, None)
    }
}

impl UpeTrackStep {
    /// The same step, with every stage's result kept for display
    /// ([`explain::StepExplanation`]); the output is the step's, bit for bit.
    pub fn explain(
        input: &StepInput<'_>,
        settings: &UpeTrackParams,
    ) -> (StepOutput<UpeTrackReport>, explain::StepExplanation) {
        let mut e = explain::StepExplanation::default();
        let out = run_step(input, settings, Some(&mut e));
        (out, e)
    }
}

/// The stages in order; `trace` (when given) keeps what each produced.
fn run_step(
    input: &StepInput<'_>,
    settings: &UpeTrackParams,
    mut trace: Option<&mut explain::StepExplanation>,
) -> StepOutput<UpeTrackReport> {
    let mut nodes = input.previous.to_vec();
    let em_report = {
        let mut iterations = Vec::new();
        let mut observe = |it: registration::EmIteration<'_>| {
            if trace.is_some() {
                iterations.push(explain::EmStage::of(&it));
            }
        };
        let fixed: &[bool] = if settings.hidden_nodes_absorb {
            input.partly_seen
        } else {
            &[]
        };
        let em = register_observed(
            input.cloud,
            &mut nodes,
            input.visible,
            fixed,
            &settings.em(),
            &mut observe,
        );
        (em, iterations)
    };
    // The previous nodes moved as the visible rope moved together: what
    // the rules below take as "the previous frame".
    let previous: Vec<Vec3> = match settings.follow_shared_motion {
        true => match shared_motion(
            input.previous,
            &nodes,
            input.visible,
            libm::sqrt(settings.min_variance),
        ) {
            Some(motion) => input.previous.iter().map(|p| motion.apply(p)).collect(),
            None => input.previous.to_vec(),
        },
        false => input.previous.to_vec(),
    };
    let em = {
        let (em, iterations) = em_report;
        if settings.anchor_across_only {
            occlusion::hold_anchors_along_rope(&mut nodes, &previous, input.visible);
        }
        if let Some(t) = trace.as_deref_mut() {
            t.em = iterations;
            t.registered = nodes.clone();
        }
        em
    };
    let coefficients = settings.upe(input.frame_interval);
    let (upe, sweeps) =
        estimate_hidden_with_sweeps(&mut nodes, input.visible, &previous, &coefficients);
    if let Some(t) = trace.as_deref_mut() {
        t.sweeps = sweeps;
        t.end_runs = occlusion::hidden_end_runs(input.visible);
        t.estimated = nodes.clone();
    }
    let length = match (input.rest_length, settings.conserve_length) {
        (Some(l), true) => {
            let ends = conserve_end_lengths(&mut nodes, input.visible, l);
            let middle = conserve_middle_lengths(&mut nodes, input.visible, &previous, l);
            LengthReport {
                runs: ends.runs + middle.runs,
                largest_change: ends.largest_change.max(middle.largest_change),
            }
        }
        _ => LengthReport::default(),
    };
    // The table, fitted once when a stage needs it; no plane found: no
    // evidence against.
    let table: core::cell::OnceCell<Option<Plane>> = core::cell::OnceCell::new();
    let free_space = match (&input.evidence, settings.free_space) {
        (Some(e), true) if input.visible.contains(&false) => {
            let seen: Vec<Vec3> = nodes
                .iter()
                .zip(input.visible)
                .filter(|(_, &v)| v)
                .map(|(p, _)| *p)
                .collect();
            // The table only if the visible rope rests on it: the surface
            // no hidden node can be inside.
            let resting = core::cell::OnceCell::new();
            // Where a hidden rope may be: somewhere the images allow one,
            // not inside the table the rope rests on.
            let may_hide = |p: &Vec3| {
                e.sight(p).allows_hidden()
                    && !resting
                        .get_or_init(|| {
                            table
                                .get_or_init(|| fit_table(e))
                                .filter(|t| t.carries(&seen, e.radius))
                        })
                        .is_some_and(|t| t.hides_inside(e, p))
            };
            clear_free_space(&mut nodes, input.visible, &may_hide)
        }
        _ => FreeSpaceReport::default(),
    };
    let m = input.previous.len();
    // `l0 = L0 / (M - 1)`.
    let rest_spacing = input.rest_length.map(|l| l / m.saturating_sub(1) as f64);
    let slide::HiddenEnds { head, tail } = slide::HiddenEnds::of(input.visible);
    let keep_ends = settings.keep_end_run_spacing;
    let extension = match (
        input.rest_length,
        &input.evidence,
        settings.extend_short_ends,
    ) {
        (Some(l), Some(e), true) => {
            // A hidden end keeps its length by its spacing instead.
            let open = OpenEnds {
                head: !(keep_ends && head > 0),
                tail: !(keep_ends && tail > 0),
            };
            let under = settings.extend_under_occluders;
            let (longer, report) = extend_short_ends(&nodes, l, open, &|p| {
                e.shows_rope_at(p) || (under && e.hides_rope_at(p))
            });
            nodes = longer;
            report
        }
        _ => ExtensionReport::default(),
    };
    let emerged = match (rest_spacing, &input.evidence, settings.follow_emerged_ends) {
        (Some(spacing), Some(e), true) => {
            let reach = emerging::explained_reach(spacing, e.radius);
            let hidden_near = |p: &Vec3, r: f64| e.hidden_around(p, r);
            // On the table, or lifted off it into the air.
            let on_surface = |line: &[Vec3]| {
                table
                    .get_or_init(|| fit_table(e))
                    .as_ref()
                    .is_none_or(|t| lies_on(t, line, e.radius))
                    || e.stands_free(line)
            };
            let view = InView {
                cloud: input.cloud,
                not_rope: input.not_rope,
                hidden_near: &hidden_near,
                on_surface: &on_surface,
            };
            let laid = follow_emerged_ends(&mut nodes, input.visible, &view, reach, spacing);
            let (longer, past) =
                follow_rope_past_ends(&nodes, input.visible, &view, reach, spacing);
            nodes = longer;
            EmergedReport {
                past_ends: past,
                ..laid
            }
        }
        _ => EmergedReport::default(),
    };
    // An end that followed rope past it is no hidden run to keep: its
    // nodes now lie between that rope and the rest.
    let kept_run = |run: usize, added: f64| if added > 0.0 { 0 } else { run };
    let (head, tail) = (
        kept_run(head, emerged.past_ends.head),
        kept_run(tail, emerged.past_ends.tail),
    );
    let smooth = settings.smooth_resampling;
    let kept = match (rest_spacing, keep_ends) {
        // No extension was added at a hidden end, so the hidden runs are
        // still the first `head` and last `tail` points. (Fewer than two
        // nodes: no middle to spread, `None`.)
        (Some(spacing), true) => {
            // Past its estimated curve a hidden end goes on only where a
            // hidden rope may be: not into free space.
            let allows = |p: &Vec3| match (&input.evidence, settings.free_space) {
                (Some(e), true) => e.sight(p).allows_hidden(),
                _ => true,
            };
            resample_with_end_runs_at_rest(&nodes, head, tail, m, spacing, smooth, &allows)
        }
        _ => None,
    };
    let resampled = kept.unwrap_or_else(|| resample(&nodes, m, smooth));
    if let Some(t) = trace {
        t.before_resampling = nodes;
        t.resampled = resampled.clone();
    }
    StepOutput {
        nodes: resampled,
        visible: input.visible.to_vec(),
        report: UpeTrackReport {
            em,
            upe,
            length,
            free_space,
            extension,
            emerged,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::camera::CameraIntrinsics;
    use alloc::vec::Vec;

    #[test]
    fn the_step_caps_a_hidden_end_at_the_rest_length_only_when_asked() {
        // Ten nodes 1 cm apart; the cloud covers nodes 0-6, the tail 7-9 is
        // hidden; the rope is known to be 8 cm long, the nodes span 9.
        let previous: Vec<Vec3> = (0..10)
            .map(|i| Vec3::new(i as f64 * 0.01, 0.0, 0.6))
            .collect();
        let cloud: Vec<Vec3> = (0..=60)
            .map(|k| Vec3::new(k as f64 * 0.001, 0.0, 0.6))
            .collect();
        let visible: Vec<bool> = (0..10).map(|i| i < 7).collect();
        let camera = CameraIntrinsics::D435I_640X480;
        let input = |rest_length| StepInput {
            previous: &previous,
            cloud: &cloud,
            visible: &visible,
            partly_seen: &[],
            camera: &camera,
            evidence: None,
            rest_length,
            frame_interval: 1.0 / crate::perception::camera::DEFAULT_FPS,
            not_rope: &[],
        };
        let length = |n: &[Vec3]| n.windows(2).map(|w| (w[1] - w[0]).norm()).sum::<f64>();
        // The whole-rope cap, with the paper's resampling after it.
        let p = UpeTrackParams {
            keep_end_run_spacing: false,
            ..UpeTrackParams::default()
        };
        let capped = UpeTrackStep.step(&input(Some(0.08)), &p);
        assert!(
            capped.report.length.runs == 1 && length(&capped.nodes) < 0.0801,
            "{}",
            length(&capped.nodes)
        );
        let free = UpeTrackStep.step(&input(None), &p);
        assert!(
            free.report.length.runs == 0 && length(&free.nodes) > 0.082,
            "{}",
            length(&free.nodes)
        );
        let off = UpeTrackParams {
            conserve_length: false,
            ..p
        };
        assert_eq!(
            UpeTrackStep
                .step(&input(Some(0.08)), &off)
                .report
                .length
                .runs,
            0
        );
        // A rope known to be 10 cm: the default resampling keeps the hidden
        // tail (three segments from its anchor, node 6) at the rest spacing,
        // 10 / 9 cm; resampled as a whole, it gets the 9 cm rope's share.
        let kept = UpeTrackStep.step(&input(Some(0.10)), &UpeTrackParams::default());
        let tail = length(&kept.nodes[6..]);
        assert!((tail - 3.0 * 0.10 / 9.0).abs() < 1e-9, "{tail}");
        let spread = UpeTrackStep.step(&input(Some(0.10)), &p);
        let share = 3.0 * length(&spread.nodes) / 9.0;
        assert!((length(&spread.nodes[6..]) - share).abs() < 1e-3 && share < 0.031);
    }

    #[test]
    fn the_step_moves_a_hidden_end_out_of_free_space_only_when_asked() {
        use crate::perception::evidence::fixture::Table;
        use crate::perception::segmentation::Rect;
        // A table at 0.6 m, an occlusion rectangle over the right half; the
        // visible nodes lie under it, the hidden tip sticks out over free
        // table to the left.
        let table = Table::new(64, 48, 60.0, 600);
        let frame = table.frame();
        let rects = [Rect {
            x: 32,
            y: 0,
            w: 32,
            h: 48,
        }];
        let evidence = table.evidence(&frame, &rects, 0.0075);
        let camera = table.camera;
        let previous = table.tip_along_row_24();
        let cloud = table.rope_along_row_24();
        let visible = [true, true, true, false, false, false];
        let input = StepInput {
            previous: &previous,
            cloud: &cloud,
            visible: &visible,
            partly_seen: &[],
            camera: &camera,
            evidence: Some(evidence),
            rest_length: None,
            frame_interval: 1.0 / crate::perception::camera::DEFAULT_FPS,
            not_rope: &[],
        };
        let p = UpeTrackParams::default();
        let on = UpeTrackStep.step(&input, &p);
        assert_eq!(
            (on.report.free_space.found, on.report.free_space.runs_moved),
            (3, 1),
            "{:?}",
            on.report.free_space
        );
        assert!(on.nodes[3..]
            .iter()
            .all(|n| evidence.sight(n).allows_hidden()));
        let off = UpeTrackParams {
            free_space: false,
            ..p
        };
        let kept = UpeTrackStep.step(&input, &off);
        assert_eq!(kept.report.free_space.runs_moved, 0);
        assert!(kept.nodes[3..]
            .iter()
            .any(|n| !evidence.sight(n).allows_hidden()));
    }

    /// A table at 0.6 m (64x48 px, focal 60) and eight nodes 4 px apart
    /// along row 24 at 0.59 m, columns 14-42, known to be 9 spacings long
    /// (two short); the cloud on the visible nodes. Rope pixels over `rope`
    /// columns, a surface at 0.5 m over `front` columns.
    fn short_rope_step(
        rope: core::ops::Range<usize>,
        front: core::ops::Range<usize>,
        visible: &[bool],
        p: &UpeTrackParams,
    ) -> ExtensionReport {
        use crate::perception::evidence::fixture::Table;
        let mut table = Table::new(64, 48, 60.0, 600);
        for y in 22..27 {
            for x in rope.clone() {
                table.mask.data[y * 64 + x] = true;
            }
            for x in front.clone() {
                table.depth[y * 64 + x] = 500;
            }
        }
        let frame = table.frame();
        let evidence = table.evidence(&frame, &[], 0.0075);
        let at = |u: f64| table.at(u, 24.0, 0.59);
        let previous: Vec<Vec3> = (0..8).map(|i| at(14.0 + 4.0 * i as f64)).collect();
        let seen = |u: f64| visible[((u - 14.0) / 4.0).round().clamp(0.0, 7.0) as usize];
        let cloud: Vec<Vec3> = (0..=140)
            .map(|k| 14.0 + k as f64 * 0.2)
            .filter(|&u| seen(u))
            .map(at)
            .collect();
        let spacing = (previous[1] - previous[0]).norm();
        let input = StepInput {
            previous: &previous,
            cloud: &cloud,
            visible,
            partly_seen: &[],
            camera: &table.camera,
            evidence: Some(evidence),
            rest_length: Some(9.0 * spacing),
            frame_interval: 1.0 / crate::perception::camera::DEFAULT_FPS,
            not_rope: &[],
        };
        UpeTrackStep.step(&input, p).report.extension
    }

    #[test]
    fn the_step_gives_length_back_at_visible_ends_and_under_occluders_when_asked() {
        let p = UpeTrackParams::default();
        let spread = UpeTrackParams {
            keep_end_run_spacing: false,
            ..p
        };
        let open = UpeTrackParams {
            extend_under_occluders: false,
            ..p
        };
        // Rope pixels all along: a hidden end keeps its length by its
        // spacing and is not extended; spread with the rest, it is.
        let mut head_hidden = [true; 8];
        head_hidden[..2].fill(false);
        let r = short_rope_step(0..64, 0..0, &head_hidden, &p);
        assert!(r.head == 0.0 && r.tail > 0.0, "{r:?}");
        assert!(short_rope_step(0..64, 0..0, &head_hidden, &spread).head > 0.0);
        let mut tail_hidden = [true; 8];
        tail_hidden[6..].fill(false);
        let r = short_rope_step(0..64, 0..0, &tail_hidden, &p);
        assert!(r.tail == 0.0 && r.head > 0.0, "{r:?}");
        assert!(short_rope_step(0..64, 0..0, &tail_hidden, &spread).tail > 0.0);
        // Rope pixels a little past the nodes, then free table before the
        // head and something in front past the tail. EM draws the end nodes
        // in, so both ends take back what lies over rope pixels; only the
        // tail goes on under the occluder, and only when asked.
        let all = [true; 8];
        let under = short_rope_step(12..45, 45..64, &all, &p);
        let not = short_rope_step(12..45, 45..64, &all, &open);
        assert!(
            not.tail > 0.0 && under.tail > not.tail + 0.01,
            "{under:?} {not:?}"
        );
        assert_eq!(under.head, not.head);
    }
}
