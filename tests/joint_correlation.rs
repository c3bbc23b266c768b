//! The joint correlation sampled futures draw with (`JointCorrelation`, `dmbn calibrate
//! --fit correlation`): a drawn step's joints vary together as the file's correlation says,
//! independently without one or when asked; the file carries it and refuses a bad one by name.
#![cfg(not(target_arch = "wasm32"))]

mod support;

use std::process::Command;

use dmbn::futures::{draw_futures, JointDraws, Sampling};
use dmbn::imitate::Task;
use dmbn::model::{read_header, JointCorrelation};
use dmbn::predict::{Observations, Predictor};
use dmbn::sim::{episode, Action};

fn predictor() -> Predictor {
    Predictor::load(support::asset("models/attn-sim.dmbn")).unwrap()
}

/// Pearson's correlation of two columns.
fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

/// The page's default model with a correlation of its own: 1 on the diagonal, `pairs`
/// (i, j, r) off it, 0 elsewhere.
fn correlated(pairs: &[(usize, usize, f32)]) -> Predictor {
    let d = predictor().joint_count();
    let mut r = vec![0.0f32; d * d];
    for i in 0..d {
        r[i * d + i] = 1.0;
    }
    for &(i, j, v) in pairs {
        r[i * d + j] = v;
        r[j * d + i] = v;
    }
    let correlation = JointCorrelation::new("r", r, d).unwrap();
    predictor()
        .with_joint_correlation(Some(correlation))
        .unwrap()
}

/// A demonstration finished from its first 30% with one drawn step, its last: the drawn
/// step's Gaussian is the prediction there given the observations alone.
struct LastStep {
    observations: Observations,
    future: Vec<f32>,
    mean: Vec<f32>,
    sigma: Vec<f32>,
}

impl LastStep {
    fn of(p: &Predictor, action: Action, seed: u64) -> Self {
        let demo = episode(action, seed, 64).unwrap();
        let steps = Task::Finish.steps(demo.len(), 5).unwrap();
        let observations = Observations::from_sequence(&demo, &steps.observed).unwrap();
        let future = demo.times()[steps.predicted_from..].to_vec();
        let marginal = p
            .predict(&observations, &future[future.len() - 1..], 0.5)
            .unwrap();
        let (mean, sigma) = (marginal.joint_mean_at(0), marginal.joint_sigma_at(0));
        LastStep {
            observations,
            future,
            mean: mean.to_vec(),
            sigma: sigma.to_vec(),
        }
    }

    /// `samples` futures drawn so (as drawn, τ 1, every future from all the observations:
    /// each drawn step from the one Gaussian), each one's drawn joints standardised by it.
    fn standardised(&self, p: &Predictor, samples: usize, sampling: Sampling) -> Vec<Vec<f32>> {
        let sampling = Sampling {
            samples,
            grid: 1,
            temperature: 1.0,
            oversample: 1,
            bootstrap: false,
            ..sampling
        };
        let futures = draw_futures(p, &self.observations, &self.future, 0.5, &sampling).unwrap();
        (futures.iter())
            .map(|f| {
                let x = &f.drawn[0].1;
                let z = x.iter().zip(&self.mean).zip(&self.sigma);
                z.map(|((x, m), s)| (x - m) / s).collect()
            })
            .collect()
    }
}

#[test]
fn a_drawn_step_s_joints_vary_as_the_correlation_says() {
    let d = predictor().joint_count();
    // Joint values 0 and 1 together (0.9), 2 against 3 (-0.8), the rest on their own.
    let p = correlated(&[(0, 1, 0.9), (2, 3, -0.8)]);
    let case = LastStep::of(&p, Action::Move, 626_262);
    let (observations, future) = (&case.observations, &case.future[..]);
    // Drawn as such (representatives would spread wider than the Gaussian), along every
    // direction of R; one column per joint value.
    let standardised = |joints: JointDraws| {
        let sampling = Sampling {
            joints,
            components: None,
            ..Sampling::default()
        };
        let rows = case.standardised(&p, 200, sampling);
        let column = |j: usize| rows.iter().map(|z| z[j] as f64).collect::<Vec<f64>>();
        (0..d).map(column).collect::<Vec<_>>()
    };
    let z = standardised(JointDraws::Auto);
    let (r01, r23, r04) = (
        pearson(&z[0], &z[1]),
        pearson(&z[2], &z[3]),
        pearson(&z[0], &z[4]),
    );
    assert!((r01 - 0.9).abs() < 0.06, "r01 {r01}");
    assert!((r23 + 0.8).abs() < 0.08, "r23 {r23}");
    assert!(r04.abs() < 0.2, "r04 {r04}");
    // Each joint keeps its Gaussian: unit variance once standardised.
    for (j, column) in z.iter().enumerate() {
        let var = column.iter().map(|v| v * v).sum::<f64>() / column.len() as f64;
        assert!((0.75..1.3).contains(&var), "joint {j}: variance {var}");
    }
    let independent = standardised(JointDraws::Independent);
    let r01 = pearson(&independent[0], &independent[1]);
    assert!(r01.abs() < 0.2, "independent r01 {r01}");
    // Asked for correlated joints, a file without a correlation is refused by name.
    let plain = predictor().with_joint_correlation(None).unwrap();
    let sampling = Sampling {
        joints: JointDraws::Correlated,
        ..Sampling::default()
    };
    let err = draw_futures(&plain, observations, future, 0.5, &sampling).unwrap_err();
    assert!(err.to_string().contains("joints"), "{err}");
    let wrong = JointCorrelation::new("r", vec![1.0, 0.0, 0.0, 1.0], 2).unwrap();
    let err = predictor().with_joint_correlation(Some(wrong)).unwrap_err();
    assert!(err.to_string().contains("2 × 2"), "{err}");
}

#[test]
fn drawn_along_one_principal_direction_only_the_leading_joints_move() {
    // Joint values 0 and 1 together (0.9: R's leading direction, λ 1.9), 2 against 3 (-0.5).
    let p = correlated(&[(0, 1, 0.9), (2, 3, -0.5)]);
    let case = LastStep::of(&p, Action::Grasp, 515_151);
    let draw = |components| {
        let sampling = Sampling {
            components,
            ..Sampling::default()
        };
        case.standardised(&p, 20, sampling)
    };
    let (one, all) = (draw(Some(1)), draw(None));
    for (z, z_all) in one.iter().zip(&all) {
        // Joints 0 and 1 move as one, the rest stay at their means.
        assert!((z[0] - z[1]).abs() < 1e-3 * (1.0 + z[0].abs()), "{z:?}");
        assert!(z[2..].iter().all(|v| v.abs() < 1e-4), "{z:?}");
        // The same draw along R's every direction: the leading one plus the others.
        assert!(z_all[2..].iter().any(|v| v.abs() > 1e-3), "{z_all:?}");
    }
    // Spread along that direction: √1.9 · ε, so a standard deviation near 1.4.
    let var = one.iter().map(|z| (z[0] * z[0]) as f64).sum::<f64>() / one.len() as f64;
    assert!(
        (0.8..3.8).contains(&var),
        "variance along the leading direction {var}"
    );
    let bad = Sampling {
        components: Some(0),
        ..Sampling::default()
    };
    let err = draw_futures(&p, &case.observations, &case.future, 0.5, &bad).unwrap_err();
    assert!(err.to_string().contains("components"), "{err}");
}

#[test]
fn dmbn_calibrate_fits_the_correlation_and_a_bad_one_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let data = tmp.path().join("data");
    support::simulated_dataset(&data, 0..4, &Action::ALL, 420_000);
    let model = support::asset("models/attn-sim.dmbn");
    let before = read_header(&std::fs::read(&model).unwrap()).unwrap();
    let calibrate = |fit: &str, out: &std::path::Path, more: &[&str]| {
        let run = Command::new(env!("CARGO_BIN_EXE_dmbn"))
            .arg("calibrate")
            .args(["--model".as_ref(), model.as_os_str()])
            .args(["--data".as_ref(), data.as_os_str()])
            .args(["--ids", "0-3", "--fit", fit])
            .args(more)
            .arg("--out")
            .arg(out)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&run.stdout).to_string();
        assert!(
            run.status.success(),
            "{stdout}{}",
            String::from_utf8_lossy(&run.stderr)
        );
        (read_header(&std::fs::read(out).unwrap()).unwrap(), stdout)
    };
    // The correlation alone: the σ scales as they were; 2 drawn steps of 8 sequences, a
    // region per action and drawn step (each with a centre, the mean pose its draws are
    // nearest, and a phase: the step's, the end at 1).
    let out = tmp.path().join("correlated.dmbn");
    let (header, stdout) = calibrate("correlation", &out, &[]);
    assert!(stdout.contains("16 steps of 8 sequences"), "{stdout}");
    assert!(
        stdout.contains("4 regions") && stdout.contains("region 3 at phase 1.00: "),
        "{stdout}"
    );
    assert_eq!(header.joint_sigma_scales(), before.joint_sigma_scales());
    let d = header.config.joint_count();
    let r = header.joint_correlation().unwrap().expect("a correlation");
    assert_eq!((r.regions(), r.values().len()), (4, 4 * d * d));
    assert_eq!(
        header.joint_correlation_centres.as_ref().unwrap().len(),
        4 * d
    );
    let phases = header.joint_correlation_phases.clone().unwrap();
    assert!(phases[0] < 0.9 && phases[1] == 1.0 && phases[2] < 0.9 && phases[3] == 1.0);
    for region in 0..4 {
        let values = r.region_values(region);
        assert!((values.iter().enumerate()).any(|(k, v)| k / d != k % d && v.abs() > 0.3));
    }
    // A region per action over both drawn steps: 2, no phases.
    let (actions, stdout) = calibrate(
        "correlation",
        &tmp.path().join("actions.dmbn"),
        &["--regions", "actions"],
    );
    assert!(stdout.contains("region 1: 8 steps"), "{stdout}");
    let two = actions.joint_correlation().unwrap().unwrap();
    assert_eq!((two.regions(), actions.joint_correlation_phases), (2, None));
    // Pooled (`--regions 1`): one R, no centres.
    let (pooled, _) = calibrate(
        "correlation",
        &tmp.path().join("pooled.dmbn"),
        &["--regions", "1"],
    );
    let one = pooled.joint_correlation().unwrap().unwrap();
    assert_eq!((one.regions(), pooled.joint_correlation_centres), (1, None));
    let run = Command::new(env!("CARGO_BIN_EXE_dmbn"))
        .args(["calibrate", "--regions", "0", "--fit", "correlation"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        !run.status.success() && stderr.contains("--regions"),
        "{stderr}"
    );
    // The σ scales alone keep the file's correlation.
    let (sigma, _) = calibrate("sigma", &tmp.path().join("sigma.dmbn"), &[]);
    assert_eq!(sigma.joint_correlation, before.joint_correlation);
    assert_ne!(sigma.joint_sigma_scales(), before.joint_sigma_scales());
    // A file whose correlation is not one is refused, naming the field.
    let bytes = std::fs::read(&out).unwrap();
    for (field, bad) in [
        ("joint_correlation", serde_json::json!([1.0, 2.0])),
        (
            "joint_correlation",
            serde_json::json!(vec![1.5f32; 2 * d * d]),
        ),
        ("joint_correlation_centres", serde_json::json!([0.0, 1.0])),
        (
            "joint_correlation_phases",
            serde_json::json!([0.5, 1.0, 2.0, 1.0]),
        ),
    ] {
        let err =
            Predictor::from_bytes(&support::with_header_field(&bytes, field, bad)).unwrap_err();
        assert!(err.to_string().contains(field), "{err}");
    }
    // `--joints independent` draws other futures than the file's correlation.
    let sample = |joints: &str, dir: &str| {
        let run = Command::new(env!("CARGO_BIN_EXE_dmbn"))
            .arg("sample")
            .args(["--model".as_ref(), out.as_os_str()])
            .args(["--data".as_ref(), data.as_os_str()])
            .args([
                "--sequence",
                "1/move",
                "--observe",
                "0,5,10",
                "--samples",
                "3",
            ])
            .args(["--joints", joints, "--out"])
            .arg(tmp.path().join(dir))
            .output()
            .unwrap();
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        std::fs::read_to_string(tmp.path().join(dir).join("samples.json")).unwrap()
    };
    let correlated = sample("auto", "correlated");
    assert!(correlated.contains("\"correlated\""), "{correlated}");
    assert_ne!(correlated, sample("independent", "independent"));
}
