use rand::SeedableRng;
use rand_pcg::Pcg64;
use wasm_bindgen::prelude::*;

use super::argument::{choice, optional_index, seed};
use super::Episode;
use crate::augment::{EvalMode, EvalSequence};

/// One of the paper's evaluation sequences of an episode (t, p or f), with explicit time
/// stamps: what the page shows the model.
#[wasm_bindgen]
pub struct EvalEpisode {
    inner: EvalSequence,
}

#[wasm_bindgen]
impl EvalEpisode {
    /// Number of steps T.
    #[wasm_bindgen(getter, js_name = len)]
    pub fn steps(&self) -> usize {
        self.inner.sequence.len()
    }

    /// Shown frames, `Uint8Array(T × S × S × 3)`.
    pub fn frames(&self) -> Vec<u8> {
        self.inner.sequence.frames.clone()
    }

    /// Shown joints, `Float32Array(T × D)`.
    pub fn joints(&self) -> Vec<f32> {
        self.inner.sequence.joints.values().to_vec()
    }

    /// Time stamp of every step, `Float32Array(T)` (permuted for p).
    pub fn times(&self) -> Vec<f32> {
        self.inner.times.clone()
    }
}

#[wasm_bindgen]
impl Episode {
    /// The evaluation sequence `mode` of this episode: `"t"` (unchanged), `"p"` (time stamps
    /// permuted with `seed`) or `"f"` (steps `freezeFrom..freezeTo` show step `freezeFrom`;
    /// the whole episode when they are omitted). Throws on an unknown mode or seed.
    #[wasm_bindgen(js_name = evalSequence)]
    pub fn eval_sequence(
        &self,
        #[wasm_bindgen(unchecked_param_type = "string")] mode: JsValue,
        #[wasm_bindgen(js_name = seed, unchecked_param_type = "number")] seed_value: JsValue,
        #[wasm_bindgen(js_name = freezeFrom, unchecked_param_type = "number | undefined")]
        freeze_from: JsValue,
        #[wasm_bindgen(js_name = freezeTo, unchecked_param_type = "number | undefined")]
        freeze_to: JsValue,
    ) -> Result<EvalEpisode, JsError> {
        let mode: EvalMode = choice(&mode, "mode", "\"t\", \"p\" or \"f\"")?;
        let mut rng = Pcg64::seed_from_u64(seed(&seed_value)?);
        let freeze_from = optional_index(&freeze_from, "freezeFrom")?;
        let freeze_to = optional_index(&freeze_to, "freezeTo")?;
        let freeze = freeze_from.map(|from| (from, freeze_to.unwrap_or(self.sequence().len())));
        Ok(EvalEpisode {
            inner: EvalSequence::build(mode, self.sequence(), freeze, &mut rng),
        })
    }
}
