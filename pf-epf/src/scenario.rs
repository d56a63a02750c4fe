//! Synthetic versions of the paper's three test sequences (Section 4), whose videos are not
//! available, and three stress scenes a user's own data can look like: the true paths, the
//! detections they produce (noise, missed detections, clutter) and the init data a user
//! would give.
//!
//! | scenario | targets | what makes it hard |
//! |---|---|---|
//! | [`Scenario::VanPlane`] | 2 | at frame 6 the plane's detection is nearer the van's last position than the plane's own; the straight dynamics tell them apart (Fig. 2) |
//! | [`Scenario::WalkingMen`] | 3 | two men cross at frame 6, where their detections are almost equidistant from both, then turn; the third walks back (Fig. 3, Table 1) |
//! | [`Scenario::Ants`] | 6 | erratic, similar ants (speed changes, stops, turns) seen at five sparse frames 0, 10, 25, 35, 45 (Fig. 4, Table 2) |
//! | [`Scenario::Crossing`] | 2 | straight paths at 3 units a frame crossing at 30° (T1 at the crossing point at frame 32, T2 at 34), detection noise sd 1, twice the tracker's default `r` |
//! | [`Scenario::SparseAnts`] | 6 | erratic ants in a 50 × 50 dish seen every 5th frame (about 6 units between observations), with sharp turns and stops |
//! | [`Scenario::SimultaneousTurns`] | 3 | three targets abreast, 4 units apart, turning left then right by 90° at the same frames (noise sd 0.5) |
//!
//! Init data are the noisy detections of each target at the first
//! [`Scenario::init_frames`] observed frames: two for the paper's tests (the two anterior
//! positions its energies need), eight for the stress scenes (enough for the tracker to
//! estimate `q` and `r` from them, [`crate::data::Init::estimate_noise`]).

use crate::data::{Detection, Detections, Init, InitRow};
use crate::error::{EpfError, Result};
use crate::geometry::Vec2;
use pf_core::params::ParamError;
use rand::{Rng, RngExt};
use rand_distr::{Distribution, Normal, Poisson, StandardNormal};
use serde::{Deserialize, Serialize};

/// The paper's three test sequences and three stress scenes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Scenario {
    /// Two targets (Fig. 2).
    VanPlane,
    /// Three targets (Fig. 3).
    WalkingMen,
    /// Six targets at sparse frames (Fig. 4).
    Ants,
    /// Two targets crossing at 30°, detection noise sd 1 (stress scene).
    Crossing,
    /// Six erratic ants seen every 5th frame (stress scene).
    SparseAnts,
    /// Three targets turning at the same frames (stress scene).
    SimultaneousTurns,
}

impl Scenario {
    /// The paper's three, in its order (what [`crate::experiments::section4()`] runs).
    pub const ALL: [Scenario; 3] = Scenario::PAPER;

    /// The paper's three tests, in its order.
    pub const PAPER: [Scenario; 3] = [Scenario::VanPlane, Scenario::WalkingMen, Scenario::Ants];

    /// The three stress scenes: crossing with noise larger than the default `r`, sparse
    /// frames with sharp turns and stops, simultaneous turns.
    pub const STRESS: [Scenario; 3] = [
        Scenario::Crossing,
        Scenario::SparseAnts,
        Scenario::SimultaneousTurns,
    ];

    /// Every scenario: the paper's, then the stress scenes.
    pub const EVERY: [Scenario; 6] = [
        Scenario::VanPlane,
        Scenario::WalkingMen,
        Scenario::Ants,
        Scenario::Crossing,
        Scenario::SparseAnts,
        Scenario::SimultaneousTurns,
    ];

    /// The name used on the command line and in file names.
    pub fn name(self) -> &'static str {
        match self {
            Scenario::VanPlane => "van-plane",
            Scenario::WalkingMen => "walking-men",
            Scenario::Ants => "ants",
            Scenario::Crossing => "crossing",
            Scenario::SparseAnts => "sparse-ants",
            Scenario::SimultaneousTurns => "simultaneous-turns",
        }
    }

    /// A title for figures and tables.
    pub fn title(self) -> &'static str {
        match self {
            Scenario::VanPlane => "Van–plane",
            Scenario::WalkingMen => "Walking men",
            Scenario::Ants => "Ants",
            Scenario::Crossing => "Crossing at 30°, noise sd 1",
            Scenario::SparseAnts => "Ants every 5th frame",
            Scenario::SimultaneousTurns => "Simultaneous turns",
        }
    }

    /// Whether this is one of the paper's tests ([`Scenario::PAPER`]).
    pub fn is_paper(self) -> bool {
        Scenario::PAPER.contains(&self)
    }

    /// The frame the paper's energy table is about (`t` in Figs. 2–4); for the stress
    /// scenes, the frame where they are hardest (the crossing, the ants' middle
    /// observation, the first turn).
    pub fn key_frame(self) -> i64 {
        match self {
            Scenario::VanPlane | Scenario::WalkingMen => 6,
            Scenario::Ants => 35,
            Scenario::Crossing => CROSSING_FRAME as i64,
            Scenario::SparseAnts => 70,
            Scenario::SimultaneousTurns => TURNS[0].0 as i64 + 1,
        }
    }

    /// The observed frames.
    pub fn frames(self) -> Vec<i64> {
        match self {
            Scenario::VanPlane | Scenario::WalkingMen => (0..=12).collect(),
            Scenario::Ants => vec![0, 10, 25, 35, 45],
            Scenario::Crossing => (0..=64).collect(),
            Scenario::SparseAnts => (0..=20).map(|i| 5 * i).collect(),
            Scenario::SimultaneousTurns => (0..=48).collect(),
        }
    }

    /// How many of the first observed frames make the init data.
    pub fn init_frames(self) -> usize {
        if self.is_paper() { 2 } else { 8 }
    }

    /// Standard deviation of the detection noise.
    pub fn noise(self) -> f64 {
        match self {
            Scenario::VanPlane | Scenario::WalkingMen => 0.15,
            Scenario::Ants | Scenario::SparseAnts => 0.3,
            Scenario::Crossing => 1.0,
            Scenario::SimultaneousTurns => 0.5,
        }
    }
}

impl std::str::FromStr for Scenario {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        pf_core::names::parse_name("scenario", &Scenario::EVERY, Scenario::name, s)
    }
}

/// A scenario with its nuisance rates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioConfig {
    /// Which sequence.
    pub scenario: Scenario,
    /// Mean number of clutter detections per frame (Poisson), uniform over the scene.
    pub clutter: f64,
    /// Probability that a target's detection is missed at a tracked frame.
    pub miss: f64,
}

impl ScenarioConfig {
    /// The clean scenario.
    pub fn new(scenario: Scenario) -> Self {
        ScenarioConfig {
            scenario,
            clutter: 0.0,
            miss: 0.0,
        }
    }

    /// Check the rates.
    ///
    /// # Errors
    /// [`EpfError::Param`] for a clutter rate outside `[0, 10⁴]` or a miss
    /// probability outside `[0, 1)`.
    pub fn validate(&self) -> Result<()> {
        if !(self.clutter >= 0.0 && self.clutter <= MAX_CLUTTER) {
            return Err(EpfError::Param(ParamError {
                name: "clutter",
                value: self.clutter,
                reason: "the mean clutter per frame must lie in [0, 10⁴]",
            }));
        }
        if !(self.miss >= 0.0 && self.miss < 1.0) {
            return Err(EpfError::Param(ParamError {
                name: "miss",
                value: self.miss,
                reason: "the miss probability must lie in [0, 1)",
            }));
        }
        Ok(())
    }
}

/// The largest mean clutter per frame a scenario accepts: far more detections than targets
/// already at 100, and each frame's detections are kept in memory.
pub const MAX_CLUTTER: f64 = 1e4;

/// One target's true path at the observed frames.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TruthTrack {
    /// Target id.
    pub target: i64,
    /// Position per observed frame.
    pub position: Vec<[f64; 2]>,
}

/// A simulated sequence.
#[derive(Debug, Clone, PartialEq)]
pub struct Simulation {
    /// The scenario and rates.
    pub config: ScenarioConfig,
    /// Observed frames.
    pub frames: Vec<i64>,
    /// True paths, one per target.
    pub truth: Vec<TruthTrack>,
    /// Detections of every observed frame (the init frames too), labelled with their source.
    pub detections: Detections,
    /// The init data (each target's detections at the first [`Scenario::init_frames`]
    /// frames).
    pub init: Init,
}

impl Simulation {
    /// Target `k`'s true position at `frame`, if observed.
    pub fn truth_at(&self, k: usize, frame: i64) -> Option<Vec2> {
        let i = self.frames.iter().position(|&f| f == frame)?;
        let p = self.truth.get(k)?.position[i];
        Some(Vec2::new(p[0], p[1]))
    }
}

/// Van (T1) along the x-axis, plane (T2) diving towards the van's track: at frame 6 the
/// plane's detection (11, 1) is √2 from the van's position at 5 but 6 from its own.
fn van_plane(t: f64) -> [Vec2; 2] {
    [
        Vec2::new(2.0 * t, 0.0),
        Vec2::new(11.0 + 0.05 * (t - 6.0), 1.0 - 6.0 * (t - 6.0)),
    ]
}

/// T1 walks out and back (a smooth U-turn); T2 and T3 walk side by side, converge and cross
/// at frame 6 a metre apart in x, then turn away from each other.
fn walking_men(t: f64) -> [Vec2; 3] {
    let turn = (t - 7.0).max(0.0);
    [
        Vec2::new(
            4.0 + 10.0 * (std::f64::consts::PI * t / 14.0).sin(),
            6.0 + 0.6 * t,
        ),
        Vec2::new(
            2.0 * t - 0.5 * turn * turn / 2.0,
            6.0 - t + 0.4 * turn * turn,
        ),
        Vec2::new(2.0 * t + 1.0, -6.0 + t - 0.4 * turn * turn),
    ]
}

/// The frame where the crossing scene's paths meet.
const CROSSING_FRAME: f64 = 32.0;

/// The crossing scene's speed (units per frame).
const CROSSING_SPEED: f64 = 3.0;

/// Two targets at [`CROSSING_SPEED`], T1 along the x-axis through the origin at
/// [`CROSSING_FRAME`], T2 at 30° to it through the origin two frames later: they come
/// closest (5.8 apart, about 6 detection-noise sd) between those frames, so the scene tests
/// noise larger than the tracker assumes rather than an ambiguous crossing.
fn crossing(t: f64) -> [Vec2; 2] {
    let s = CROSSING_SPEED * (t - CROSSING_FRAME);
    let s2 = CROSSING_SPEED * (t - CROSSING_FRAME - 2.0);
    let a = std::f64::consts::FRAC_PI_6;
    [Vec2::new(s, 0.0), Vec2::new(s2 * a.cos(), s2 * a.sin())]
}

/// The turns of [`simultaneous_turns`]: `(first frame, frames, total angle)`.
const TURNS: [(f64, f64, f64); 2] = [
    (20.0, 6.0, std::f64::consts::FRAC_PI_2),
    (34.0, 6.0, -std::f64::consts::FRAC_PI_2),
];

/// The spacing of [`simultaneous_turns`]' formation.
const TURNS_SPACING: f64 = 4.0;

/// The common heading of [`simultaneous_turns`] at frame `t`: 0, turned by each of
/// [`TURNS`] at a constant rate over its frames.
fn turn_heading(t: f64) -> f64 {
    TURNS
        .iter()
        .map(|&(t0, n, angle)| angle * ((t - t0) / n).clamp(0.0, 1.0))
        .sum()
}

/// Three targets abreast, [`TURNS_SPACING`] apart across the direction of motion, at unit
/// speed with the same heading [`turn_heading`]: they never cross, and all three turn left
/// by 90° over frames 20–26 and back right over 34–40 (15° a frame). The
/// position integrates the heading frame by frame (the heading of frame `f` moves the
/// target from `f` to `f + 1`).
fn simultaneous_turns(frames: &[i64]) -> Vec<Vec<Vec2>> {
    let last = frames.last().copied().unwrap_or(0);
    let mut centre = Vec2::new(-20.0, 0.0);
    let mut out: Vec<Vec<Vec2>> = (0..3).map(|_| Vec::with_capacity(frames.len())).collect();
    for f in 0..=last {
        if frames.contains(&f) {
            // The offset turns with the formation: targets stay abreast.
            let h = turn_heading(f as f64);
            let across = Vec2::new(-h.sin(), h.cos());
            for (k, path) in out.iter_mut().enumerate() {
                path.push(centre + across * (TURNS_SPACING * (k as f64 - 1.0)));
            }
        }
        let h = turn_heading(f as f64 + 0.5);
        centre += Vec2::new(h.cos(), h.sin());
    }
    out
}

/// Six ants in a dish `[−25, 25]²` (walls reflect them), moving frame by frame: speed
/// drawn from U(0.8, 1.6) (mean 1.2, so about 6 units between observations 5 frames
/// apart), with probability 0.05 per frame a stop of 3–8 frames, with probability 0.08 per
/// frame a sharp turn of ±(60°–120°), and a heading wobble N(0, 0.1²) rad per frame; they
/// start on a circle of radius 15.
fn sparse_ants<R: Rng + ?Sized>(frames: &[i64], rng: &mut R) -> Vec<Vec<Vec2>> {
    let last = frames.last().copied().unwrap_or(0);
    let half = 25.0;
    let mut out: Vec<Vec<Vec2>> = (0..6).map(|_| Vec::with_capacity(frames.len())).collect();
    for (k, path) in out.iter_mut().enumerate() {
        let phi = std::f64::consts::TAU * k as f64 / 6.0;
        let mut x = Vec2::new(15.0 * phi.cos(), 15.0 * phi.sin());
        let mut heading = phi + std::f64::consts::PI + rng.random_range(-1.5..1.5);
        let mut speed: f64 = rng.random_range(0.8..1.6);
        let mut stopped = 0u32;
        for f in 0..=last {
            if frames.contains(&f) {
                path.push(x);
            }
            if stopped > 0 {
                stopped -= 1;
                continue;
            }
            if rng.random_bool(0.05) {
                stopped = rng.random_range(3..=8);
                continue;
            }
            if rng.random_bool(0.2) {
                speed = rng.random_range(0.8..1.6);
            }
            if rng.random_bool(0.08) {
                let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
                heading += sign
                    * rng.random_range(
                        std::f64::consts::FRAC_PI_3..2.0 * std::f64::consts::FRAC_PI_3,
                    );
            }
            let dh: f64 = StandardNormal.sample(rng);
            heading += 0.1 * dh;
            let mut next = x + Vec2::new(heading.cos(), heading.sin()) * speed;
            // Reflect off the dish's walls.
            for c in 0..2 {
                if next[c].abs() > half {
                    next[c] = next[c].signum() * 2.0 * half - next[c];
                    heading = if c == 0 {
                        std::f64::consts::PI - heading
                    } else {
                        -heading
                    };
                }
            }
            x = next;
        }
    }
    out
}

/// Six ants with piecewise motion frame by frame: speed redrawn (or a stop) with
/// probability 0.15 per frame, heading perturbed by N(0, 0.2²) rad per frame and turned
/// by up to ±π/2 with probability 0.05; they start on a circle of radius 12.
fn ants<R: Rng + ?Sized>(frames: &[i64], rng: &mut R) -> Vec<Vec<Vec2>> {
    let last = *frames.last().unwrap_or(&0);
    let mut out: Vec<Vec<Vec2>> = (0..6).map(|_| Vec::with_capacity(frames.len())).collect();
    for (k, path) in out.iter_mut().enumerate() {
        let phi = std::f64::consts::TAU * k as f64 / 6.0;
        let mut x = Vec2::new(12.0 * phi.cos(), 12.0 * phi.sin());
        let mut heading = phi + rng.random_range(-1.0..1.0);
        let mut speed = rng.random_range(0.3..1.0);
        for f in 0..=last {
            if frames.contains(&f) {
                path.push(x);
            }
            if rng.random_bool(0.15) {
                speed = if rng.random_bool(0.3) {
                    0.0
                } else {
                    rng.random_range(0.2..1.2)
                };
            }
            if rng.random_bool(0.05) {
                heading += rng.random_range(-1.0..1.0) * std::f64::consts::FRAC_PI_2;
            }
            let dh: f64 = StandardNormal.sample(rng);
            heading += 0.2 * dh;
            x += Vec2::new(heading.cos(), heading.sin()) * speed;
        }
    }
    out
}

/// Simulate one sequence.
///
/// # Errors
/// Invalid rates.
pub fn simulate<R: Rng + ?Sized>(cfg: &ScenarioConfig, rng: &mut R) -> Result<Simulation> {
    cfg.validate()?;
    let sc = cfg.scenario;
    let frames = sc.frames();
    let paths: Vec<Vec<Vec2>> = match sc {
        Scenario::VanPlane => (0..2)
            .map(|k| frames.iter().map(|&f| van_plane(f as f64)[k]).collect())
            .collect(),
        Scenario::WalkingMen => (0..3)
            .map(|k| frames.iter().map(|&f| walking_men(f as f64)[k]).collect())
            .collect(),
        Scenario::Ants => ants(&frames, rng),
        Scenario::Crossing => (0..2)
            .map(|k| frames.iter().map(|&f| crossing(f as f64)[k]).collect())
            .collect(),
        Scenario::SparseAnts => sparse_ants(&frames, rng),
        Scenario::SimultaneousTurns => simultaneous_turns(&frames),
    };
    // The scene: the paths' bounding box, padded, where clutter falls.
    let (mut lo, mut hi) = (Vec2::repeat(f64::INFINITY), Vec2::repeat(f64::NEG_INFINITY));
    for p in paths.iter().flatten() {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    lo -= Vec2::repeat(3.0);
    hi += Vec2::repeat(3.0);
    let noise = Normal::new(0.0, sc.noise()).expect("positive noise");
    let clutter = if cfg.clutter > 0.0 {
        Some(Poisson::new(cfg.clutter).map_err(|_| {
            EpfError::Param(ParamError {
                name: "clutter",
                value: cfg.clutter,
                reason: "not a Poisson rate",
            })
        })?)
    } else {
        None
    };
    let mut rows = Vec::new();
    let mut init_rows = Vec::new();
    let n_init = sc.init_frames();
    for (i, &f) in frames.iter().enumerate() {
        let is_init = i < n_init;
        let mut frame_rows = Vec::new();
        for (k, path) in paths.iter().enumerate() {
            if !is_init && rng.random_bool(cfg.miss) {
                continue;
            }
            let y = path[i] + Vec2::new(noise.sample(rng), noise.sample(rng));
            if is_init {
                init_rows.push(InitRow {
                    target: k as i64,
                    frame: f,
                    position: y,
                });
            }
            frame_rows.push(Detection {
                frame: f,
                position: y,
                target: Some(k as i64),
            });
        }
        if let (Some(c), false) = (clutter.as_ref(), is_init) {
            let n = c.sample(rng) as usize;
            for _ in 0..n {
                frame_rows.push(Detection {
                    frame: f,
                    position: Vec2::new(rng.random_range(lo.x..hi.x), rng.random_range(lo.y..hi.y)),
                    target: None,
                });
            }
        }
        // Detections are unlabelled: their order within a frame must not give the answer.
        for j in (1..frame_rows.len()).rev() {
            frame_rows.swap(j, rng.random_range(0..=j));
        }
        rows.extend(frame_rows);
    }
    // Init rows grouped by target, as a user would write them.
    init_rows.sort_by_key(|r| (r.target, r.frame));
    Ok(Simulation {
        config: *cfg,
        truth: paths
            .iter()
            .enumerate()
            .map(|(k, p)| TruthTrack {
                target: k as i64,
                position: p.iter().map(|v| [v.x, v.y]).collect(),
            })
            .collect(),
        frames,
        detections: Detections::new(rows)?,
        init: Init::new(&init_rows)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use pf_core::mc::stream_rng;

    fn sim(s: Scenario, seed: u64) -> Simulation {
        simulate(&ScenarioConfig::new(s), &mut stream_rng(seed, 0)).unwrap()
    }

    /// Every scenario parses back from its name; `ALL` stays the paper's three.
    #[test]
    fn names_round_trip_and_lists_partition() {
        for s in Scenario::EVERY {
            assert_eq!(s.name().parse::<Scenario>().unwrap(), s);
            assert_eq!(s.is_paper(), Scenario::PAPER.contains(&s));
            assert_ne!(Scenario::PAPER.contains(&s), Scenario::STRESS.contains(&s));
        }
        assert_eq!(Scenario::ALL, Scenario::PAPER);
    }

    /// Crossing: speed 3, 30° apart, at the crossing point two frames apart; 57 tracked
    /// frames.
    #[test]
    fn crossing_meets_at_thirty_degrees() {
        let s = sim(Scenario::Crossing, 1);
        let k = Scenario::Crossing.key_frame();
        assert!(s.truth_at(0, k).unwrap().norm() < 1e-12);
        assert!(s.truth_at(1, k + 2).unwrap().norm() < 1e-12);
        let v0 = s.truth_at(0, k + 1).unwrap() - s.truth_at(0, k).unwrap();
        let v1 = s.truth_at(1, k + 1).unwrap() - s.truth_at(1, k).unwrap();
        assert!((v0.norm() - 3.0).abs() < 1e-12 && (v1.norm() - 3.0).abs() < 1e-12);
        assert!((v0.angle(&v1).to_degrees() - 30.0).abs() < 1e-9);
        assert_eq!(s.init.targets()[0].points.len(), 8);
        assert_eq!(s.frames.len() - 8, 57);
    }

    /// Simultaneous turns: always 4 apart, heading turned by 90° after the first turn and
    /// back after the second.
    #[test]
    fn turns_keep_the_formation() {
        let s = sim(Scenario::SimultaneousTurns, 1);
        for &f in &s.frames {
            let (a, b, c) = (
                s.truth_at(0, f).unwrap(),
                s.truth_at(1, f).unwrap(),
                s.truth_at(2, f).unwrap(),
            );
            assert!(((a - b).norm() - 4.0).abs() < 1e-9 && ((b - c).norm() - 4.0).abs() < 1e-9);
        }
        let step = |f: i64| s.truth_at(1, f + 1).unwrap() - s.truth_at(1, f).unwrap();
        assert!((step(10) - Vec2::new(1.0, 0.0)).norm() < 1e-9);
        assert!((step(28) - Vec2::new(0.0, 1.0)).norm() < 1e-9);
        assert!((step(44) - Vec2::new(1.0, 0.0)).norm() < 1e-9);
    }

    /// Sparse ants: six, seen every 5th frame, about 6 units between observations (the
    /// moving frames' mean speed 1.2 × 5, less the stops), inside the dish.
    #[test]
    fn sparse_ants_move_about_six_units_between_observations() {
        let (mut sum, mut n, mut stops) = (0.0, 0usize, 0usize);
        for seed in 0..50 {
            let s = sim(Scenario::SparseAnts, seed);
            assert_eq!(s.truth.len(), 6);
            for t in &s.truth {
                for w in t.position.windows(2) {
                    let d = (Vec2::new(w[1][0], w[1][1]) - Vec2::new(w[0][0], w[0][1])).norm();
                    sum += d;
                    n += 1;
                    stops += usize::from(d < 1e-12);
                    assert!(w[1][0].abs() <= 25.0 && w[1][1].abs() <= 25.0);
                }
            }
        }
        let mean = sum / n as f64;
        assert!((4.0..7.0).contains(&mean), "mean displacement {mean}");
        assert!(stops > 0, "some ants stop for a whole observation gap");
    }
}
