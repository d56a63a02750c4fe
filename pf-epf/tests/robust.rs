//! The tracker on data it was not built around: `q` and `r` estimated from the init tracks,
//! gates that grow while a target coasts, lost tracks reported and re-acquired, and the
//! stress scenes against the constant-velocity Kalman reference.

use pf_core::mc::{Par, mean_and_se, stream_rng};
use pf_epf::association::Association;
use pf_epf::data::{Detection, Detections, Init, InitRow, NoiseEstimate};
use pf_epf::experiments::scenes::{SceneMethod, ScenesConfig, scenes};
use pf_epf::geometry::Vec2;
use pf_epf::scenario::{Scenario, ScenarioConfig, simulate};
use pf_epf::tracker::{Record, TrackStatus, TrackerConfig, track};
use rand::RngExt;
use rand_distr::{Distribution, StandardNormal};

fn normal2<R: rand::Rng + ?Sized>(rng: &mut R) -> Vec2 {
    Vec2::new(StandardNormal.sample(rng), StandardNormal.sample(rng))
}

/// Tracks drawn from the estimator's own model: the true path's chord residual over a gap
/// `Δ` is `N(0, q²Δ)`, detections add `N(0, r²)`; frame gaps 1 or 2 at random.
fn model_tracks(
    q: f64,
    r: f64,
    n_targets: usize,
    n_points: usize,
    seed: u64,
    rep: u64,
) -> Vec<Vec<(i64, Vec2)>> {
    let mut rng = stream_rng(seed, rep);
    (0..n_targets)
        .map(|_| {
            let mut frames = vec![0i64];
            for _ in 1..n_points {
                let gap = rng.random_range(1..=2);
                frames.push(frames.last().unwrap() + gap);
            }
            let mut x = vec![Vec2::zeros(), Vec2::new(1.0, 0.5)];
            for i in 2..n_points {
                let rho =
                    (frames[i] - frames[i - 1]) as f64 / (frames[i - 1] - frames[i - 2]) as f64;
                let dt = (frames[i] - frames[i - 1]) as f64;
                let next =
                    x[i - 1] + (x[i - 1] - x[i - 2]) * rho + normal2(&mut rng) * (q * dt.sqrt());
                x.push(next);
            }
            frames
                .iter()
                .zip(&x)
                .map(|(&f, &p)| (f, p + normal2(&mut rng) * r))
                .collect()
        })
        .collect()
}

/// The raw moment estimates are unbiased under their model: over 2000 replications (3
/// targets × 8 uneven frames each) their means lie within 4 standard errors of `q²` and
/// `r²`; the floored `r̂` has a mean within 10 % of `r` (its Jensen bias is a few per cent
/// at this size).
#[test]
fn noise_estimates_are_unbiased_on_their_model() {
    let (q, r) = (0.4, 0.3);
    let est: Vec<NoiseEstimate> = (0..2000)
        .map(|rep| {
            let t = model_tracks(q, r, 3, 8, 11, rep);
            NoiseEstimate::from_tracks(t.iter().map(|v| v.as_slice())).unwrap()
        })
        .collect();
    let (mq, sq) = mean_and_se(&est.iter().map(|e| e.q2_raw).collect::<Vec<_>>());
    let (mr, sr) = mean_and_se(&est.iter().map(|e| e.r2_raw).collect::<Vec<_>>());
    println!(
        "q²: {mq:.4} ± {sq:.4} (truth {}), r²: {mr:.4} ± {sr:.4} (truth {})",
        q * q,
        r * r
    );
    assert!((mq - q * q).abs() < 4.0 * sq, "q² {mq} ± {sq}");
    assert!((mr - r * r).abs() < 4.0 * sr, "r² {mr} ± {sr}");
    let (m, _) = mean_and_se(&est.iter().map(|e| e.r).collect::<Vec<_>>());
    assert!((m - r).abs() < 0.1 * r, "r̂ {m}");
}

/// On the simulator's stress scenes, whose init frames are straight (`q = 0`), the raw
/// estimates' means over 400 replications are within 4 standard errors of the simulator's
/// `r²` and of 0 for `q²`; the `r̂` used is within 15 % of the simulator's `r` on average.
#[test]
fn noise_estimates_recover_the_simulators_values() {
    for s in [Scenario::Crossing, Scenario::SimultaneousTurns] {
        let est: Vec<NoiseEstimate> = (0..400)
            .map(|rep| {
                let sim = simulate(&ScenarioConfig::new(s), &mut stream_rng(5, rep)).unwrap();
                sim.init.estimate_noise().unwrap()
            })
            .collect();
        let r = s.noise();
        let (mq, sq) = mean_and_se(&est.iter().map(|e| e.q2_raw).collect::<Vec<_>>());
        let (mr, sr) = mean_and_se(&est.iter().map(|e| e.r2_raw).collect::<Vec<_>>());
        let (m, se) = mean_and_se(&est.iter().map(|e| e.r).collect::<Vec<_>>());
        println!(
            "{}: q² {mq:.4} ± {sq:.4}, r² {mr:.4} ± {sr:.4} (truth {}), r̂ {m:.3} ± {se:.3}",
            s.name(),
            r * r
        );
        assert!(mq.abs() < 4.0 * sq, "{s:?} q² {mq} ± {sq}");
        assert!((mr - r * r).abs() < 4.0 * sr, "{s:?} r² {mr} ± {sr}");
        assert!((m - r).abs() < 0.15 * r, "{s:?} r̂ {m}");
    }
}

/// Two targets on parallel lines (y = 0 and y = 10, unit speed); target 0's detections stop
/// at frames 10–20 and resume at 21. It coasts for `lost_after` = 3 frames, is reported
/// lost from frame 13, stays on its line while lost (its prediction extends its known
/// velocity, known to about 0.01 per frame from detections of noise sd 0.01: under 1 unit
/// from the truth), and takes its own detection again at frame 21.
/// Target 1 is associated at every frame.
#[test]
fn a_target_whose_detections_stop_is_lost_then_reacquired() {
    let init = Init::new(
        &(0..4)
            .flat_map(|f| {
                [0, 1].map(|k| InitRow {
                    target: k,
                    frame: f,
                    position: Vec2::new(f as f64, 10.0 * k as f64),
                })
            })
            .collect::<Vec<_>>(),
    )
    .unwrap();
    let mut rows = Vec::new();
    let mut rng = stream_rng(3, 0);
    for f in 4..=40 {
        for k in [0i64, 1] {
            if k == 0 && (10..=20).contains(&f) {
                continue;
            }
            rows.push(Detection {
                frame: f,
                position: Vec2::new(f as f64, 10.0 * k as f64) + normal2(&mut rng) * 0.01,
                target: Some(k),
            });
        }
    }
    let dets = Detections::new(rows).unwrap();
    for association in [Association::Energy, Association::Nearest] {
        let cfg = TrackerConfig {
            association,
            n_particles: 300,
            ..TrackerConfig::default()
        };
        let res = track(&dets, &init, &cfg, Record::Tracks, &mut stream_rng(4, 0)).unwrap();
        let t0 = &res.tracks[0];
        for (i, &f) in res.frames.iter().enumerate() {
            let expected = match f {
                10..=12 => TrackStatus::Coasting,
                13..=20 => TrackStatus::Lost,
                _ => TrackStatus::Associated,
            };
            assert_eq!(t0.status[i], expected, "{association:?} frame {f}");
            assert_eq!(
                t0.detection[i].is_some(),
                expected == TrackStatus::Associated
            );
            if let Some(j) = t0.detection[i] {
                assert_eq!(dets.rows()[j].target, Some(0), "{association:?} frame {f}");
            }
            let p = t0.position[i];
            assert!(
                (Vec2::new(p[0], p[1]) - Vec2::new(f as f64, 0.0)).norm() < 1.0,
                "{association:?} frame {f}: {p:?}"
            );
            assert_eq!(res.tracks[1].status[i], TrackStatus::Associated);
        }
    }
}

/// The same target with `reacquire = false` (the paper's tracker) still reports its status:
/// whatever happens after frame 20, frames 10–12 are coasting and 13–20 lost.
#[test]
fn the_papers_tracker_reports_status_too() {
    let init = Init::new(
        &(0..4)
            .flat_map(|f| {
                [0, 1].map(|k| InitRow {
                    target: k,
                    frame: f,
                    position: Vec2::new(f as f64, 10.0 * k as f64),
                })
            })
            .collect::<Vec<_>>(),
    )
    .unwrap();
    let rows: Vec<Detection> = (4..=30)
        .flat_map(|f| [0i64, 1].map(|k| (f, k)))
        .filter(|&(f, k)| !(k == 0 && (10..=20).contains(&f)))
        .map(|(f, k)| Detection {
            frame: f,
            position: Vec2::new(f as f64, 10.0 * k as f64),
            target: Some(k),
        })
        .collect();
    let dets = Detections::new(rows).unwrap();
    let cfg = TrackerConfig {
        n_particles: 100,
        reacquire: false,
        ..TrackerConfig::default()
    };
    let res = track(&dets, &init, &cfg, Record::Tracks, &mut stream_rng(4, 0)).unwrap();
    for (i, &f) in res.frames.iter().enumerate() {
        let want = match f {
            10..=12 => Some(TrackStatus::Coasting),
            13..=20 => Some(TrackStatus::Lost),
            _ if f < 10 => Some(TrackStatus::Associated),
            _ => None,
        };
        if let Some(w) = want {
            assert_eq!(res.tracks[0].status[i], w, "frame {f}");
        }
    }
}

/// The stress scenes with default flags (q̂, r̂ from the init tracks), 60 replications: on
/// the crossing (noise sd 1, twice the default r), the default tracker (energy) keeps its
/// targets: the fraction of target-frames without a detection is at most the Kalman
/// reference's plus 0.02 (the reference misses about one in a hundred by its 99 % gate),
/// and the RMSE is at most 4 times the reference's and under 10 (the particle filter's
/// velocity is the last chord of two detections of noise sd 1, the reference's a Kalman
/// average; before the robust tracker: 95 of 114 target-frames without a detection and
/// RMSE 64). The numbers are printed (`-- --nocapture`).
#[test]
fn crossing_with_default_flags_keeps_its_targets() {
    let cfg = ScenesConfig {
        replications: 60,
        n_particles: 200,
        seed: 9,
        par: Par::Rayon,
    };
    let res = scenes(&cfg).unwrap();
    for s in &res.scenes {
        println!(
            "{} (q̂ {:.3}, r̂ {:.3}):",
            s.scenario.name(),
            s.q_hat.0,
            s.r_hat.0
        );
        for m in &s.methods {
            println!(
                "  {:16} error {:.3} ± {:.3}  RMSE {:.3} ± {:.3}  missing {:.3} ± {:.3}  lost {:.3}",
                m.method.label(),
                m.error_rate.0,
                m.error_rate.1,
                m.rmse.0,
                m.rmse.1,
                m.missing.0,
                m.missing.1,
                m.lost.0
            );
        }
    }
    let crossing = &res.scenes[0];
    assert_eq!(crossing.scenario, Scenario::Crossing);
    let kf = crossing
        .methods
        .iter()
        .find(|m| m.method == SceneMethod::CvKalman)
        .unwrap();
    let m = crossing
        .methods
        .iter()
        .find(|m| m.method == SceneMethod::Energy)
        .unwrap();
    assert!(
        m.missing.0 <= kf.missing.0 + 0.02,
        "missing {:?} vs {:?}",
        m.missing,
        kf.missing
    );
    assert!(
        m.rmse.0 <= 4.0 * kf.rmse.0 && m.rmse.0 < 10.0,
        "RMSE {:?} vs {:?}",
        m.rmse,
        kf.rmse
    );
}
