//! The path-space and fixed-lag estimators on the batch filter ([`SmoothedAr1`],
//! [`FixedLagTerms`]): against their direct formulas on the recorded lines, against the
//! generic filter's estimates in distribution, and the same bits for one thread and two.

use pf_core::filter::{
    BatchConfig, BatchFilter, BatchObserver, BatchView, EssThreshold, FilterConfig, ParticleFilter,
    ResamplePolicy,
};
use pf_core::mc::{Par, mean_and_se, replicate, stream_rng};
use pf_core::models::NoisyAr1;
use pf_core::observe::{CloudRecorder, GenealogyRecorder};
use pf_smooth::em::{lag_statistics, paper_filter_config};
use pf_smooth::{AdditiveFunctional, Ar1Data, Ar1Statistics, FixedLagTerms, SmoothedAr1, Theta};

/// Section 5's data, `n` steps, from stream `s`.
fn data(n: usize, s: u64) -> Ar1Data {
    let truth = NoisyAr1::new(0.98, 0.2, 1.0).unwrap();
    Ar1Data::new(truth.simulate(n, &mut stream_rng(13, s)).1).unwrap()
}

/// Every step's weights and columns.
#[derive(Default)]
struct Record(Vec<(Vec<f64>, Vec<Vec<f64>>)>);

impl BatchObserver for Record {
    fn on_step(&mut self, v: &BatchView<'_>) {
        let n = v.n();
        let mut w = vec![0.0; n];
        v.weights_into(&mut w).expect("N weights");
        let cols = (0..v.dim())
            .map(|k| {
                let mut c = vec![0.0; n];
                v.column_into(k, &mut c).expect("column k of N");
                c
            })
            .collect();
        self.0.push((w, cols));
    }
}

/// The term of step `j` (with the term of `X_0` at `j = 1`) along a line, `x(k) = X_k`.
fn term(stats: &Ar1Statistics<'_>, j: usize, x: &dyn Fn(usize) -> f64, out: &mut [f64]) {
    if j == 1 {
        stats.initial(&x(0), out);
    }
    stats.increment(j, &x(j - 1), &x(j), out);
}

/// `Σ_i W_m^i Σ_{j ∈ js} s_j(line^i)` at step `m`.
fn weighted_terms(
    stats: &Ar1Statistics<'_>,
    w: &[f64],
    line: &dyn Fn(usize, usize) -> f64,
    js: std::ops::RangeInclusive<usize>,
    out: &mut [f64; 4],
) {
    for (i, &wi) in w.iter().enumerate() {
        let mut s = [0.0; 4];
        for j in js.clone() {
            term(stats, j, &|k| line(i, k), &mut s);
        }
        for (o, v) in out.iter_mut().zip(s) {
            *o += wi * v;
        }
    }
}

/// The joint estimate (eq. (6)) and the fixed-lag one (eq. (9)) of lag `delta`, from the
/// lines `line(m, i, k) = X_k` of particle `i` of step `m` and the weights of each step.
fn direct(
    stats: &Ar1Statistics<'_>,
    n: usize,
    delta: usize,
    weights: &dyn Fn(usize) -> Vec<f64>,
    line: &dyn Fn(usize, usize, usize) -> f64,
) -> ([f64; 4], [f64; 4]) {
    let mut joint = [0.0; 4];
    weighted_terms(stats, &weights(n), &|i, k| line(n, i, k), 1..=n, &mut joint);
    let mut lagged = [0.0; 4];
    for j in 1..=n {
        let m = (j + delta - 1).min(n);
        weighted_terms(
            stats,
            &weights(m),
            &|i, k| line(m, i, k),
            j..=j,
            &mut lagged,
        );
    }
    (joint, lagged)
}

fn close(a: &[f64], b: &[f64]) -> bool {
    a.iter()
        .zip(b)
        .all(|(x, y)| (x - y).abs() < 1e-9 * y.abs().max(1.0))
}

/// With a register as long as the data, each step's columns hold every particle's whole
/// ancestral line: the estimates must be the direct formulas on those lines, under any
/// resampling policy and chunking.
fn against_direct(policy: ResamplePolicy, delta: usize, chunk: usize) {
    let d = data(30, 5);
    let n = d.n();
    let theta = Theta::paper_start();
    let stats = Ar1Statistics::new(&d);
    let model = SmoothedAr1::new(&theta, &d, n).unwrap();
    let mut terms = FixedLagTerms::new(&model, &[delta, n + 3]).unwrap();
    let cfg = BatchConfig {
        policy,
        chunk,
        ..BatchConfig::new(40, 11)
    };
    let mut pf = BatchFilter::new(model, cfg).unwrap();
    let mut rec = Record::default();
    pf.run_observed(None, &d.filter_input(), &mut (&mut terms, &mut rec))
        .unwrap();
    let (joint, lagged) = terms.estimates(&pf.view().unwrap()).unwrap();
    let steps = &rec.0;
    assert_eq!(steps.len(), n + 1);
    let line = |m: usize, i: usize, k: usize| steps[m].1[model.lag_column(m - k)][i];
    // The sums γ of the last step are the lines' sums.
    let gamma = &steps[n].1[1..=4];
    for i in 0..40 {
        let mut s = [0.0; 4];
        for j in 1..=n {
            term(&stats, j, &|k| line(n, i, k), &mut s);
        }
        let gi: Vec<f64> = gamma.iter().map(|g| g[i]).collect();
        assert!(close(&gi, &s), "particle {i}: {gi:?} vs {s:?}");
    }
    let (dj, dl) = direct(&stats, n, delta, &|m| steps[m].0.clone(), &line);
    assert!(close(&joint.tau, &dj), "{policy:?}: {joint:?} vs {dj:?}");
    assert!(
        close(&lagged[0].tau, &dl),
        "{policy:?}, δ = {delta}: {:?} vs {dl:?}",
        lagged[0]
    );
    // A lag beyond n freezes nothing: the joint estimate, to the bit.
    assert_eq!(lagged[1], joint);
}

#[test]
fn without_resampling_the_estimators_are_the_importance_sampling_formulas() {
    against_direct(ResamplePolicy::Never, 5, 2048);
}

#[test]
fn sums_and_register_follow_the_ancestors_under_any_resampling_policy() {
    against_direct(
        ResamplePolicy::EssBelow(EssThreshold::Fraction(0.5)),
        4,
        2048,
    );
    against_direct(ResamplePolicy::Always, 7, 2048);
    against_direct(ResamplePolicy::Never, 7, 16);
    against_direct(ResamplePolicy::Always, 7, 16);
    against_direct(ResamplePolicy::Always, 1, 2048);
}

/// The generic filter's joint and fixed-lag estimates, from its recorded clouds and
/// genealogy (eqs. (6) and (9) directly).
fn generic_estimates(
    d: &Ar1Data,
    theta: &Theta,
    n_particles: usize,
    delta: usize,
    seed: u64,
) -> [f64; 8] {
    let stats = Ar1Statistics::new(d);
    let mut pf = ParticleFilter::bootstrap(
        theta.model(d.y()[0]).unwrap(),
        paper_filter_config(n_particles),
    )
    .unwrap();
    let mut rec = (CloudRecorder::new(), GenealogyRecorder::new());
    pf.run(&d.filter_input(), None, &mut stream_rng(seed, 0), &mut rec)
        .unwrap();
    let (clouds, g) = rec;
    let g = g.genealogy();
    let lines: Vec<Vec<Vec<usize>>> = (0..=d.n())
        .map(|m| {
            (0..n_particles)
                .map(|i| g.lineage_at(m, i).unwrap())
                .collect()
        })
        .collect();
    let line = |m: usize, i: usize, k: usize| clouds.clouds[k].particles[lines[m][i][k]];
    let (j, l) = direct(
        &stats,
        d.n(),
        delta,
        &|m| clouds.clouds[m].weights.clone(),
        &line,
    );
    let mut out = [0.0; 8];
    out[..4].copy_from_slice(&j);
    out[4..].copy_from_slice(&l);
    out
}

/// The batch estimates and the generic filter's agree in distribution: over 200
/// replications each, every mean within 4 standard errors of the difference.
#[test]
fn batch_and_generic_estimates_agree_in_distribution() {
    let d = data(60, 6);
    let theta = Theta::paper_start();
    let (r, n_particles, delta) = (200, 100, 8);
    let filter = paper_filter_config(n_particles);
    let batch = replicate(21, r, Par::Rayon, |_, rng| {
        let run = lag_statistics(&d, &theta, filter, &[delta], false, rng).unwrap();
        let mut out = [0.0; 8];
        out[..4].copy_from_slice(&run.joint.tau);
        out[4..].copy_from_slice(&run.fixed_lag[0].tau);
        out
    });
    let generic = replicate(22, r, Par::Rayon, |r, _| {
        generic_estimates(&d, &theta, n_particles, delta, 1000 + r as u64)
    });
    for c in 0..8 {
        let col = |v: &[[f64; 8]]| v.iter().map(|x| x[c]).collect::<Vec<f64>>();
        let (mb, sb) = mean_and_se(&col(&batch));
        let (mg, sg) = mean_and_se(&col(&generic));
        let se = (sb * sb + sg * sg).sqrt();
        assert!(
            (mb - mg).abs() < 4.0 * se,
            "component {c}: batch {mb} ± {sb}, generic {mg} ± {sg}"
        );
    }
}

/// One thread or two, several chunks: the same bits.
#[test]
fn one_thread_and_two_give_the_same_bits() {
    let d = data(80, 7);
    let theta = Theta::paper_start();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let model = SmoothedAr1::new(&theta, &d, 20).unwrap();
            let mut terms = FixedLagTerms::new(&model, &[1, 5, 20, 200]).unwrap();
            let cfg = BatchConfig {
                par: Par::Rayon,
                chunk: 512,
                ..BatchConfig::new(3000, 4)
            };
            let mut pf = BatchFilter::new(model, cfg).unwrap();
            pf.run_observed(None, &d.filter_input(), &mut terms)
                .unwrap();
            let (j, l) = terms.estimates(&pf.view().unwrap()).unwrap();
            let mut bits: Vec<u64> = j.tau.iter().map(|x| x.to_bits()).collect();
            bits.extend(l.iter().flat_map(|s| s.tau.map(f64::to_bits)));
            // The experiments' replications, on the pool, each filter on one thread.
            let f = FilterConfig::new(200);
            let reps = replicate(3, 6, Par::Rayon, |_, rng| {
                lag_statistics(&d, &theta, f, &[10], true, rng).unwrap()
            });
            for r in reps {
                bits.extend(r.joint.tau.map(f64::to_bits));
                bits.extend(r.fixed_lag[0].tau.map(f64::to_bits));
                bits.extend(r.forward.unwrap().tau.map(f64::to_bits));
            }
            bits
        })
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn a_lag_within_the_data_needs_its_register() {
    let d = data(30, 8);
    let model = SmoothedAr1::new(&Theta::paper_start(), &d, 5).unwrap();
    assert!(FixedLagTerms::new(&model, &[5, 31, 1000]).is_ok());
    let e = FixedLagTerms::new(&model, &[6]).unwrap_err().to_string();
    assert!(e.contains("lag"), "{e}");
    assert!(FixedLagTerms::new(&model, &[0]).is_err());
}
