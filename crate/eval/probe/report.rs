//! What the probe measured: the rows, the table and the warnings about diverged heads.
use serde::Serialize;

use super::checks::DIVERGENCE_FACTOR;
use crate::eval::MeanCi;

/// The rows of the paper's Table 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum ProbeRow {
    /// The trained DMBN's encoders fed t = 0: what the content alone tells.
    Null,
    /// An untrained DMBN of the same architecture (a new one per seed).
    Random,
    /// The trained DMBN.
    Dmbn,
    /// The trained DMBN-PTE (z = g(e(x) + P(t))).
    #[serde(rename = "DMBN-PTE")]
    Pte,
}

impl ProbeRow {
    pub const ALL: [ProbeRow; 4] = [
        ProbeRow::Null,
        ProbeRow::Random,
        ProbeRow::Dmbn,
        ProbeRow::Pte,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ProbeRow::Null => "Null",
            ProbeRow::Random => "Random",
            ProbeRow::Dmbn => "DMBN",
            ProbeRow::Pte => "DMBN-PTE",
        }
    }
}

/// A head that diverged (see [`diverged`](super::diverged)).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Divergence {
    /// `"image"` or `"joint"`.
    pub modality: &'static str,
    pub seed: u64,
    /// Its test MSE.
    pub mse: f64,
}

/// One row of the table: test MSE of the time regression per seed, and its mean with CI.
#[derive(Debug, Clone, Serialize)]
pub struct ProbeResult {
    pub row: ProbeRow,
    pub image: MeanCi,
    pub joint: MeanCi,
    pub image_mse: Vec<f64>,
    pub joint_mse: Vec<f64>,
    /// The heads that diverged: their cells are not to be trusted.
    pub diverged: Vec<Divergence>,
}

impl ProbeResult {
    /// The seeds whose `modality` (`"image"` / `"joint"`) head diverged.
    pub fn diverged_seeds(&self, modality: &str) -> Vec<u64> {
        self.diverged
            .iter()
            .filter(|d| d.modality == modality)
            .map(|d| d.seed)
            .collect()
    }
}

/// Everything the probe measured.
#[derive(Debug, Clone, Serialize)]
pub struct ProbeReport {
    pub rows: Vec<ProbeResult>,
    pub train_sequences: usize,
    pub test_sequences: usize,
    pub train_steps: usize,
    pub test_steps: usize,
    /// Variance of the test steps' times: the MSE of predicting their mean time.
    pub test_time_variance: f64,
    /// MSE above which a head counts as diverged ([`DIVERGENCE_FACTOR`] × the variance).
    pub divergence_limit: f64,
    pub seeds: u64,
    pub seconds: f64,
    /// Everything that makes numbers of this run doubtful: diverged heads (from
    /// [`probe`](super::probe)), a split too small ([`split_warnings`](super::split_warnings), added by the caller that knows the ids).
    pub warnings: Vec<String>,
}

/// MSE ×1e-3 with two decimals.
fn milli(v: f64) -> String {
    format!("{:.2}", v * 1e3)
}

impl ProbeReport {
    /// The table in the paper's layout: MSE ×1e-3, mean (95% CI low, high); cells with a
    /// diverged head marked ⚠; then Var(t) of the test steps and the warnings.
    pub fn markdown(&self) -> String {
        let cell = |m: &MeanCi, flagged: bool| {
            format!(
                "{} ({}, {}){}",
                milli(m.mean),
                milli(m.mean - m.ci95),
                milli(m.mean + m.ci95),
                if flagged { " ⚠" } else { "" }
            )
        };
        let mut out = String::from(
            "| Model | Image Encoder Loss (1e-3) | Joint Encoder Loss (1e-3) |\n|---|---:|---:|\n",
        );
        for r in &self.rows {
            out.push_str(&format!(
                "| {} | {} | {} |\n",
                r.row.name(),
                cell(&r.image, !r.diverged_seeds("image").is_empty()),
                cell(&r.joint, !r.diverged_seeds("joint").is_empty())
            ));
        }
        out.push_str(&format!(
            "\nVar(t) of the {} test steps: {} ×1e-3 (the MSE of predicting the mean time); a \
             head above {} ×1e-3 ({DIVERGENCE_FACTOR}×Var(t)) counts as diverged (⚠).\n",
            self.test_steps,
            milli(self.test_time_variance),
            milli(self.divergence_limit)
        ));
        if !self.warnings.is_empty() {
            out.push_str("\nWarnings:\n\n");
            for w in &self.warnings {
                out.push_str(&format!("- {w}\n"));
            }
        }
        out
    }
}

/// The warning for the diverged heads of `r`'s `modality`, if any.
pub(super) fn divergence_warning(
    r: &ProbeResult,
    modality: &'static str,
    seeds: u64,
    var_t: f64,
) -> Option<String> {
    let bad: Vec<&Divergence> = r
        .diverged
        .iter()
        .filter(|d| d.modality == modality)
        .collect();
    if bad.is_empty() {
        return None;
    }
    let worst =
        bad.iter().map(|d| d.mse).fold(
            f64::NEG_INFINITY,
            |a, b| if b.is_nan() || b > a { b } else { a },
        );
    let cell = if modality == "image" {
        r.image
    } else {
        r.joint
    };
    Some(format!(
        "{} {modality}: {} of {seeds} heads diverged (seeds {:?}; test MSE up to {} ×1e-3, \
         cell mean {} ±{} ×1e-3) — above {DIVERGENCE_FACTOR}×Var(t) = {} ×1e-3, where \
         predicting the mean time scores Var(t) = {} ×1e-3; the heads overfit the training \
         encodings or extrapolated, so this cell says nothing about the encoder",
        r.row.name(),
        bad.len(),
        bad.iter().map(|d| d.seed).collect::<Vec<_>>(),
        milli(worst),
        milli(cell.mean),
        milli(cell.ci95),
        milli(DIVERGENCE_FACTOR * var_t),
        milli(var_t),
    ))
}
