//! Fig. 1's phenomenon measured: how many steps back from `t` all `N` particle paths share
//! one ancestor (the coalescence delay `τ_t` of Section 4, "all active trajectories at index
//! `k` have a common ancestor back in the past at index `k − τ_k + 1`"), over many seeded
//! filter runs, for each resampling scheme and each θ the filter runs at.
//!
//! The mechanism is measured too. Resampling at step `k` gives particle `i` of step `k − 1`
//! `ν_k^i` offspring; two lineages traced back from step `k` merge there with probability
//! `c_k = Σ_i ν_k^i (ν_k^i − 1) / (N (N − 1))`. Kingman's coalescent (the neutral
//! Wright–Fisher limit) then gives `E[τ] ≈ 2 (1 − 1/N) / c̄` steps for all `N` lineages to
//! merge. Multinomial resampling has `E[ν(ν − 1)] = N (N − 1) W²`, so `c̄ = E[Σ W²] = E[1/ESS]`
//! and `τ` grows like the ESS, i.e. like `N` when the weights are nearly even; systematic
//! resampling gives each particle `⌊N W⌋` or `⌈N W⌉` offspring, so with nearly even weights
//! almost every `ν` is 1 and lineages hardly merge.

use super::{Observations, Scale};
use crate::ar1::Theta;
use crate::error::Result;
use pf_core::filter::{FilterConfig, ParticleFilter, ResamplePolicy};
use pf_core::mc::{Par, try_replicate};
use pf_core::observe::{Observer, StepView};
use pf_core::params::at_least_one;
use pf_core::resample::Resampler;
use serde::{Deserialize, Serialize};

/// One setting of the coalescence experiment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CoalescenceSetting {
    /// A name for tables (`"true θ"`, `"EM start θ"`).
    pub label: String,
    /// The θ the filter runs at.
    pub theta: Theta,
    /// The resampling scheme (at every step, as in Section 5).
    pub resampler: Resampler,
}

/// Settings of the coalescence experiment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CoalescenceConfig {
    /// The observations (Section 5's, `n = 500`).
    pub data: Observations,
    /// Particles N (the paper's Fig. 1: 50).
    pub particles: usize,
    /// Each θ × resampler.
    pub settings: Vec<CoalescenceSetting>,
    /// Seeded runs per setting.
    pub runs: usize,
    /// Window of Fig. 1 (steps): the share of runs coalesced within it is reported.
    pub window: usize,
    /// Seed: setting `s`, run `r` uses the stream `(seed + s, r)`.
    pub seed: u64,
}

fn default_settings() -> Vec<CoalescenceSetting> {
    let mut v = Vec::with_capacity(4);
    for (label, theta) in [
        ("true θ", Theta::paper_truth()),
        ("EM start θ", Theta::paper_start()),
    ] {
        for resampler in [Resampler::Systematic, Resampler::Multinomial] {
            v.push(CoalescenceSetting {
                label: label.to_owned(),
                theta,
                resampler,
            });
        }
    }
    v
}

impl Default for CoalescenceConfig {
    fn default() -> Self {
        Self::at_scale(Scale::Default)
    }
}

impl CoalescenceConfig {
    /// Section 5's data, N = 50, systematic and multinomial at the true and the EM start θ;
    /// 20 runs per setting at `Quick`, 400 at `Default`, 2000 at `Full`.
    pub fn at_scale(scale: Scale) -> Self {
        let runs = match scale {
            Scale::Quick => 20,
            Scale::Default => 400,
            Scale::Full => 2000,
        };
        CoalescenceConfig {
            data: Observations::paper(0),
            particles: 50,
            settings: default_settings(),
            runs,
            window: 100,
            seed: 0,
        }
    }
}

/// One run: the coalescence delay at the last step and the mechanism's numbers.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CoalescenceRun {
    /// Steps back from the last step `n` to the most recent common ancestor of all `N`
    /// particles; `None` if they have none within the run (censored at `n`).
    pub delay: Option<usize>,
    /// Mean over steps of the pair-merging probability `c_k`.
    pub merge_rate: f64,
    /// Mean over steps of `ESS / N`.
    pub ess_fraction: f64,
    /// Mean over steps of the share of particles with at least one offspring.
    pub parents_fraction: f64,
    /// Mean over steps of `Σ_i (W_{k−1}^i)²` of the weights resampled at step `k`: the
    /// expected `c_k` under multinomial resampling.
    pub sum_w2: f64,
}

/// One setting over its runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CoalescenceRow {
    /// The setting.
    pub setting: CoalescenceSetting,
    /// Every run's delay (`None`: not coalesced within the `n` steps).
    pub delays: Vec<Option<usize>>,
    /// The 10 %, 25 %, 50 %, 75 %, 90 % quantiles of the delay; `None` where the quantile lies
    /// beyond `n` (censored).
    pub quantiles: [Option<usize>; 5],
    /// Share of runs whose delay is at most the window (Fig. 1 shows coalescence).
    pub within_window: f64,
    /// Share of runs coalesced within the `n` steps.
    pub within_run: f64,
    /// Mean `c̄` over runs.
    pub merge_rate: f64,
    /// Kingman's `2 (1 − 1/N) / c̄` (steps).
    pub kingman_delay: f64,
    /// Mean `ESS / N` over runs.
    pub ess_fraction: f64,
    /// Mean share of particles with offspring.
    pub parents_fraction: f64,
    /// Mean `Σ W²` over runs (the merge rate multinomial resampling would give).
    pub sum_w2: f64,
    /// Every run's numbers.
    pub runs: Vec<CoalescenceRun>,
}

/// The levels of [`CoalescenceRow::quantiles`].
pub const QUANTILE_LEVELS: [f64; 5] = [0.1, 0.25, 0.5, 0.75, 0.9];

/// The experiment's result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CoalescenceResult {
    /// Steps in each run (`n`).
    pub steps: usize,
    /// Particles N.
    pub particles: usize,
    /// The window of [`CoalescenceRow::within_window`].
    pub window: usize,
    /// One row per setting, in the config's order.
    pub rows: Vec<CoalescenceRow>,
}

/// Records every step's ancestors (into storage reserved for the whole run), ESS and the
/// offspring statistics.
#[derive(Debug, Clone, Default)]
pub struct AncestorLog {
    n: usize,
    /// `A_k^i` at `k·N + i` for `k ≥ 1` (step 0 is not stored).
    pub ancestors: Vec<usize>,
    counts: Vec<usize>,
    merge: f64,
    ess: f64,
    parents: f64,
    sum_w2: f64,
    prev_w2: f64,
    steps: usize,
}

impl AncestorLog {
    /// A log for `n` particles and up to `steps` steps.
    pub fn with_capacity(n: usize, steps: usize) -> Self {
        AncestorLog {
            n,
            ancestors: Vec::with_capacity(n * steps),
            counts: vec![0; n],
            ..Self::default()
        }
    }

    /// Steps recorded after the first.
    pub fn resampled_steps(&self) -> usize {
        self.ancestors.len() / self.n.max(1)
    }
}

impl<S> Observer<S> for AncestorLog {
    fn on_start(&mut self, n: usize) {
        self.n = n;
        self.ancestors.clear();
        self.counts.clear();
        self.counts.resize(n, 0);
        (self.merge, self.ess, self.parents, self.sum_w2) = (0.0, 0.0, 0.0, 0.0);
        (self.prev_w2, self.steps) = (0.0, 0);
    }
    fn on_step(&mut self, view: &StepView<'_, S>) {
        let n = self.n;
        self.ess += view.report.ess / n as f64;
        self.steps += 1;
        let w2 = view.weights.iter().map(|w| w * w).sum::<f64>();
        let prev_w2 = std::mem::replace(&mut self.prev_w2, w2);
        if self.steps == 1 {
            return;
        }
        self.sum_w2 += prev_w2;
        self.ancestors.extend_from_slice(view.ancestors);
        self.counts.fill(0);
        for &a in view.ancestors {
            self.counts[a] += 1;
        }
        let pairs: usize = self.counts.iter().map(|&c| c * c.saturating_sub(1)).sum();
        if n > 1 {
            self.merge += pairs as f64 / (n * (n - 1)) as f64;
        }
        self.parents += self.counts.iter().filter(|&&c| c > 0).count() as f64 / n as f64;
    }
}

/// Steps back from step `t` to the most recent step at which all particles of step `t`
/// have one common ancestor; `None` if there is none at or after step 0. `ancestors` holds
/// `A_k^i` at `(k − 1)·n + i` for `k = 1 …`; `alive` and `next` are scratch of length `n`.
pub fn coalescence_delay(
    ancestors: &[usize],
    n: usize,
    t: usize,
    alive: &mut [bool],
    next: &mut [bool],
) -> Option<usize> {
    if n <= 1 {
        return Some(0);
    }
    alive.fill(true);
    let mut count = n;
    for k in (1..=t).rev() {
        next.fill(false);
        let a = &ancestors[(k - 1) * n..k * n];
        for i in 0..n {
            if alive[i] {
                next[a[i]] = true;
            }
        }
        alive.copy_from_slice(next);
        count = alive.iter().filter(|&&b| b).count();
        if count == 1 {
            return Some(t - k + 1);
        }
    }
    (count == 1).then_some(t)
}

/// The `q`-quantile of the delays (lower order statistic), `None` if it is censored.
fn quantile(sorted: &[Option<usize>], q: f64) -> Option<usize> {
    if sorted.is_empty() {
        return None;
    }
    let i = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1;
    sorted[i]
}

/// Run the experiment.
///
/// # Errors
/// N, runs or settings 0, bad data or θ, or a filter failure.
pub fn coalescence(cfg: &CoalescenceConfig) -> Result<CoalescenceResult> {
    at_least_one("particles", cfg.particles)?;
    at_least_one("runs", cfg.runs)?;
    at_least_one("settings", cfg.settings.len())?;
    let (_, data) = cfg.data.draw()?;
    let ys = data.filter_input();
    let steps = data.n();
    let n = cfg.particles;
    let mut rows = Vec::with_capacity(cfg.settings.len());
    for (s, setting) in cfg.settings.iter().enumerate() {
        let model = setting.theta.model(data.y()[0])?;
        let fc = FilterConfig {
            n_particles: n,
            resampler: setting.resampler,
            policy: ResamplePolicy::Always,
        };
        let runs = try_replicate(
            cfg.seed.wrapping_add(s as u64),
            cfg.runs,
            Par::Rayon,
            |_, rng| -> Result<CoalescenceRun> {
                let mut pf = ParticleFilter::bootstrap(model, fc)?;
                let mut log = AncestorLog::with_capacity(n, steps + 1);
                pf.run(&ys, None, rng, &mut log)?;
                let (mut alive, mut next) = (vec![false; n], vec![false; n]);
                let delay = coalescence_delay(&log.ancestors, n, steps, &mut alive, &mut next);
                let k = log.steps.max(1) as f64;
                let m = log.resampled_steps().max(1) as f64;
                Ok(CoalescenceRun {
                    delay,
                    merge_rate: log.merge / m,
                    ess_fraction: log.ess / k,
                    parents_fraction: log.parents / m,
                    sum_w2: log.sum_w2 / m,
                })
            },
        )?;
        let delays: Vec<Option<usize>> = runs.iter().map(|r| r.delay).collect();
        let mean =
            |f: fn(&CoalescenceRun) -> f64| runs.iter().map(f).sum::<f64>() / runs.len() as f64;
        let merge_rate = mean(|r| r.merge_rate);
        let r = runs.len() as f64;
        let within =
            |w: usize| delays.iter().filter(|d| d.is_some_and(|d| d <= w)).count() as f64 / r;
        let (within_window, within_run) = (within(cfg.window), within(steps));
        // `None` (censored) sorts after every delay.
        let mut sorted = delays.clone();
        sorted.sort_by_key(|d| d.map_or(usize::MAX, |d| d));
        let quantiles = QUANTILE_LEVELS.map(|q| quantile(&sorted, q));
        rows.push(CoalescenceRow {
            setting: setting.clone(),
            delays,
            quantiles,
            within_window,
            within_run,
            merge_rate,
            kingman_delay: if merge_rate > 0.0 {
                2.0 * (1.0 - 1.0 / n as f64) / merge_rate
            } else {
                f64::INFINITY
            },
            ess_fraction: mean(|r| r.ess_fraction),
            parents_fraction: mean(|r| r.parents_fraction),
            sum_w2: mean(|r| r.sum_w2),
            runs,
        });
    }
    Ok(CoalescenceResult {
        steps,
        particles: n,
        window: cfg.window,
        rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use pf_core::genealogy::Genealogy;
    use pf_core::mc::stream_rng;

    /// The delay agrees with pf-core's genealogy (coalescence step counted back from the
    /// last step) on a hand-made genealogy and on random ones.
    #[test]
    fn the_delay_matches_the_genealogy() {
        use rand::RngExt;
        let mut rng = stream_rng(5, 0);
        for n in [1usize, 2, 3, 7] {
            for steps in [1usize, 2, 5, 30] {
                let mut g = Genealogy::new(n);
                g.push(&(0..n).collect::<Vec<_>>()).unwrap();
                let mut flat = Vec::new();
                for _ in 0..steps {
                    let a: Vec<usize> = (0..n).map(|_| rng.random_range(0..n)).collect();
                    g.push(&a).unwrap();
                    flat.extend_from_slice(&a);
                }
                let (mut al, mut nx) = (vec![false; n], vec![false; n]);
                let d = coalescence_delay(&flat, n, steps, &mut al, &mut nx);
                let expected = g.coalescence_time().map(|c| steps - c);
                assert_eq!(d, expected, "n = {n}, steps = {steps}");
            }
        }
        // Identity ancestors never merge: no common ancestor.
        let id: Vec<usize> = (0..3).chain(0..3).collect();
        let (mut al, mut nx) = (vec![false; 3], vec![false; 3]);
        assert_eq!(coalescence_delay(&id, 3, 2, &mut al, &mut nx), None);
    }

    #[test]
    fn quantiles_put_censored_runs_last() {
        let s = [Some(1), Some(2), Some(3), None];
        assert_eq!(quantile(&s, 0.5), Some(2));
        assert_eq!(quantile(&s, 0.75), Some(3));
        assert_eq!(quantile(&s, 0.9), None);
        assert_eq!(quantile(&[], 0.5), None);
    }
}
