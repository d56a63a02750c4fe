//! Synthetic versions of the paper's three test sequences (Section 4), whose videos are not
//! available: the true paths, the detections they produce (noise, missed detections,
//! clutter) and the init data a user would give.
//!
//! | scenario | targets | what makes it hard |
//! |---|---|---|
//! | [`Scenario::VanPlane`] | 2 | at frame 6 the plane's detection is nearer the van's last position than the plane's own; the straight dynamics tell them apart (Fig. 2) |
//! | [`Scenario::WalkingMen`] | 3 | two men cross at frame 6, where their detections are almost equidistant from both, then turn; the third walks back (Fig. 3, Table 1) |
//! | [`Scenario::Ants`] | 6 | erratic, similar ants (speed changes, stops, turns) seen at five sparse frames 0, 10, 25, 35, 45 (Fig. 4, Table 2) |
//!
//! Init data are the noisy detections of each target at the first two observed frames.

use crate::data::{Detection, Detections, Init, InitRow};
use crate::error::{EpfError, Result};
use crate::geometry::Vec2;
use pf_core::params::ParamError;
use rand::{Rng, RngExt};
use rand_distr::{Distribution, Normal, Poisson, StandardNormal};
use serde::{Deserialize, Serialize};

/// The three test sequences.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Scenario {
    /// Two targets (Fig. 2).
    VanPlane,
    /// Three targets (Fig. 3).
    WalkingMen,
    /// Six targets at sparse frames (Fig. 4).
    Ants,
}

impl Scenario {
    /// All three, in the paper's order.
    pub const ALL: [Scenario; 3] = [Scenario::VanPlane, Scenario::WalkingMen, Scenario::Ants];

    /// The name used on the command line and in file names.
    pub fn name(self) -> &'static str {
        match self {
            Scenario::VanPlane => "van-plane",
            Scenario::WalkingMen => "walking-men",
            Scenario::Ants => "ants",
        }
    }

    /// The frame the paper's energy table is about (`t` in Figs. 2–4).
    pub fn key_frame(self) -> i64 {
        match self {
            Scenario::VanPlane | Scenario::WalkingMen => 6,
            Scenario::Ants => 35,
        }
    }

    /// The observed frames.
    pub fn frames(self) -> Vec<i64> {
        match self {
            Scenario::VanPlane | Scenario::WalkingMen => (0..=12).collect(),
            Scenario::Ants => vec![0, 10, 25, 35, 45],
        }
    }

    /// Standard deviation of the detection noise.
    pub fn noise(self) -> f64 {
        match self {
            Scenario::VanPlane | Scenario::WalkingMen => 0.15,
            Scenario::Ants => 0.3,
        }
    }
}

impl std::str::FromStr for Scenario {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        pf_core::names::parse_name("scenario", &Scenario::ALL, Scenario::name, s)
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
    /// The init data (the first two frames' detections of each target).
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
    for (i, &f) in frames.iter().enumerate() {
        let is_init = i < 2;
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
