use std::sync::atomic::{AtomicU32, Ordering};

use wasm_bindgen::prelude::*;

use serde::Serialize;

use super::argument::{self, action, blend, bytes, choice, floats, index, observations, seed};
use super::contexts::Contexts;
use super::encoding::Encoding;
use super::imitation::Imitation;
use super::Episode;
use crate::futures::{draw_unobserved, frames_at, sample_unobserved, trajectories, Sampling};
use crate::imitate::{self, Task};
use crate::predict::{Observations, Predictor, SequencePrediction};
use crate::quality::{score_sequence, Quality, Scenario};

/// Tells models apart, so an encoding is only ever decoded (and encoded contexts only
/// represented) by the model that made it.
static NEXT_ID: AtomicU32 = AtomicU32::new(1);

/// A trained DMBN, DMBN-PTE or attentive model for inference in the browser: `Model.fromBytes(bytes)`, then
/// `predict(...)` in one call, or `encode(...)` the observations once and `decode(...)` target
/// times in as many chunks as wanted; or, as the demo page's worker does, `encodeContexts(...)`
/// each observation once, `represent(...)` the set observed, and `decode(...)`. Wraps
/// [`Predictor`], the same code the native `dmbn predict` runs.
#[wasm_bindgen(js_name = Model)]
pub struct ModelHandle {
    inner: Predictor,
    id: u32,
}

#[wasm_bindgen(js_class = Model)]
impl ModelHandle {
    /// Reads a model file (`Uint8Array`); throws on a truncated, corrupt or foreign file.
    #[wasm_bindgen(js_name = fromBytes)]
    pub fn from_bytes(
        #[wasm_bindgen(js_name = bytes, unchecked_param_type = "Uint8Array")] file: JsValue,
    ) -> Result<ModelHandle, JsError> {
        Ok(ModelHandle {
            inner: Predictor::from_bytes(&bytes(&file, "bytes")?)?,
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
        })
    }

    /// `"dmbn"`, `"pte"` or `"attn"`.
    #[wasm_bindgen(getter)]
    pub fn kind(&self) -> String {
        self.inner.model().kind().to_string()
    }

    /// The joint normalisation the model was trained with, `{mean, std}` (D values each): the
    /// statistics of its training data.
    #[wasm_bindgen(getter)]
    pub fn normalization(&self) -> Result<JsValue, JsError> {
        serde_wasm_bindgen::to_value(self.inner.normalization())
            .map_err(|e| JsError::new(&e.to_string()))
    }

    /// Frame width and height the model reads and predicts.
    #[wasm_bindgen(getter, js_name = imageSize)]
    pub fn image_size(&self) -> usize {
        self.inner.model().image_size()
    }

    /// Joint values a step (D) the model reads and predicts: 7 for the original arm's.
    #[wasm_bindgen(getter, js_name = jointCount)]
    pub fn joint_count(&self) -> usize {
        self.inner.joint_count()
    }

    /// A name for each joint value: the file's `joint_names`, or `joint 0` … `gripper`.
    #[wasm_bindgen(getter, js_name = jointNames)]
    pub fn joint_names(&self) -> Vec<String> {
        self.inner.model().config().joint_labels()
    }

    /// Predicts `targetTimes` from N observed steps: `frames` a `Uint8Array(N × S × S × 3)`
    /// (RGB, as `Episode.frames`), `joints` a `Float32Array(N × D)` (`jointCount` values a step),
    /// `times` a `Float32Array(N)` of phases in [0, 1], `blend` in [0, 1] (1 = images only,
    /// 0 = joints only). Throws on bad input.
    pub fn predict(
        &self,
        #[wasm_bindgen(unchecked_param_type = "Uint8Array")] frames: JsValue,
        #[wasm_bindgen(unchecked_param_type = "Float32Array")] joints: JsValue,
        #[wasm_bindgen(unchecked_param_type = "Float32Array")] times: JsValue,
        #[wasm_bindgen(js_name = targetTimes, unchecked_param_type = "Float32Array")]
        target_times: JsValue,
        #[wasm_bindgen(js_name = blend, unchecked_param_type = "number")] blend_value: JsValue,
    ) -> Result<Prediction, JsError> {
        let observations = self.observations(&frames, &joints, &times)?;
        let target_times = floats(&target_times, "targetTimes")?;
        let blend = blend(&blend_value)?;
        Ok(Prediction {
            inner: self.inner.predict(&observations, &target_times, blend)?,
        })
    }

    /// S sampled futures at `targetTimes` of the observations `contexts` (`encodeContexts`;
    /// as `dmbn sample` with its defaults: through the model's latent path where it has one,
    /// autoregressively otherwise) with `blend`: a `Float32Array(S × T × D)`, future by future,
    /// a row of D joint means per target. The steps imagined are the targets that are not an
    /// observed time; future s is the same for a `seed` whatever `samples` (1 to 256). Throws
    /// on bad input, contexts of another model, or targets that are all observed.
    pub fn sample(
        &self,
        contexts: &Contexts,
        #[wasm_bindgen(js_name = targetTimes, unchecked_param_type = "Float32Array")]
        target_times: JsValue,
        #[wasm_bindgen(js_name = blend, unchecked_param_type = "number")] blend_value: JsValue,
        #[wasm_bindgen(unchecked_param_type = "number")] samples: JsValue,
        #[wasm_bindgen(js_name = seed, unchecked_param_type = "number")] seed_value: JsValue,
    ) -> Result<Vec<f32>, JsError> {
        self.check_contexts(contexts)?;
        let (times, blend, sampling) =
            sampling(&target_times, &blend_value, &samples, &seed_value)?;
        let futures = sample_unobserved(&self.inner, &contexts.inner, &times, blend, &sampling)?;
        Ok(futures.iter().flat_map(|f| f.values().to_vec()).collect())
    }

    /// `sample`'s futures (the same for the same arguments: drawn once) with each one's mean
    /// frame at the last of `targetTimes`, where it ends: `{joints, frames}`, `joints` as
    /// `sample` returns them and `frames` a `Uint8Array(S × imageSize × imageSize × 3)` (RGB),
    /// future by future. The page draws the futures' joints and their final frames. Throws as
    /// `sample` does.
    #[wasm_bindgen(js_name = sampleWithFrames, unchecked_return_type = "{joints: Float32Array, frames: Uint8Array}")]
    pub fn sample_with_frames(
        &self,
        contexts: &Contexts,
        #[wasm_bindgen(js_name = targetTimes, unchecked_param_type = "Float32Array")]
        target_times: JsValue,
        #[wasm_bindgen(js_name = blend, unchecked_param_type = "number")] blend_value: JsValue,
        #[wasm_bindgen(unchecked_param_type = "number")] samples: JsValue,
        #[wasm_bindgen(js_name = seed, unchecked_param_type = "number")] seed_value: JsValue,
    ) -> Result<JsValue, JsError> {
        self.check_contexts(contexts)?;
        let (times, blend, sampling) =
            sampling(&target_times, &blend_value, &samples, &seed_value)?;
        let futures = draw_unobserved(&self.inner, &contexts.inner, &times, blend, &sampling)?;
        let joints: Vec<f32> = trajectories(&self.inner, &futures, &times)?
            .iter()
            .flat_map(|rows| rows.values().to_vec())
            .collect();
        // Where each future ends (the targets are not empty: some are imagined).
        let frames = frames_at(&self.inner, &futures, times[times.len() - 1])?.concat();
        let out = js_sys::Object::new();
        let set = |key: &str, value: JsValue| {
            js_sys::Reflect::set(&out, &key.into(), &value)
                .map_err(|_| JsError::new("could not build the futures' object"))
        };
        set("joints", js_sys::Float32Array::from(&joints[..]).into())?;
        set("frames", js_sys::Uint8Array::from(&frames[..]).into())?;
        Ok(out.into())
    }

    /// Encodes N observed steps, with the arguments of `predict` (without the target times),
    /// for `decode`. Throws on bad input.
    pub fn encode(
        &self,
        #[wasm_bindgen(unchecked_param_type = "Uint8Array")] frames: JsValue,
        #[wasm_bindgen(unchecked_param_type = "Float32Array")] joints: JsValue,
        #[wasm_bindgen(unchecked_param_type = "Float32Array")] times: JsValue,
        #[wasm_bindgen(js_name = blend, unchecked_param_type = "number")] blend_value: JsValue,
    ) -> Result<Encoding, JsError> {
        let observations = self.observations(&frames, &joints, &times)?;
        let blend = blend(&blend_value)?;
        Ok(Encoding {
            inner: self.inner.encode(&observations, blend)?,
            model: self.id,
        })
    }

    /// Encodes N observed steps one by one, with the arguments of `encode` (without the blend),
    /// for `represent`: the `Contexts` can be joined and cut first. Throws on bad input.
    #[wasm_bindgen(js_name = encodeContexts)]
    pub fn encode_contexts(
        &self,
        #[wasm_bindgen(unchecked_param_type = "Uint8Array")] frames: JsValue,
        #[wasm_bindgen(unchecked_param_type = "Float32Array")] joints: JsValue,
        #[wasm_bindgen(unchecked_param_type = "Float32Array")] times: JsValue,
    ) -> Result<Contexts, JsError> {
        let observations = self.observations(&frames, &joints, &times)?;
        Ok(Contexts {
            inner: self.inner.encode_contexts(&observations)?,
            model: self.id,
        })
    }

    /// The `Encoding` of encoded `contexts` with `blend` in [0, 1], for `decode`: what `encode`
    /// gives for the same observations. Throws when `contexts` come from another model or the
    /// blend is out of range.
    pub fn represent(
        &self,
        contexts: &Contexts,
        #[wasm_bindgen(js_name = blend, unchecked_param_type = "number")] blend_value: JsValue,
    ) -> Result<Encoding, JsError> {
        let blend = blend(&blend_value)?;
        self.check_contexts(contexts)?;
        Ok(Encoding {
            inner: self.inner.represent(&contexts.inner, blend)?,
            model: self.id,
        })
    }

    /// The prediction at `targetTimes` (a `Float32Array(M)` of finite phases) from `encoding`,
    /// as `predict` returns it. Throws when `encoding` comes from another model or a time is
    /// not finite.
    pub fn decode(
        &self,
        encoding: &Encoding,
        #[wasm_bindgen(js_name = targetTimes, unchecked_param_type = "Float32Array")]
        target_times: JsValue,
    ) -> Result<Prediction, JsError> {
        let target_times = floats(&target_times, "targetTimes")?;
        if encoding.model != self.id {
            return Err(JsError::new(
                "this encoding was made by another model: encode the observations with this one",
            ));
        }
        Ok(Prediction {
            inner: self.inner.decode(&encoding.inner, &target_times)?,
        })
    }

    /// The quality benchmark on one episode (what `dmbn score` computes per sequence):
    /// `scenario` `"interp"` (`observations` evenly spaced steps, every step scored) or
    /// `"extrap"` (the first 30% observed at 3 steps, the rest scored), with `blend`. Returns
    /// `{model, baseline}`, each with the fields `dmbn score --json` writes (`joint_rmse`,
    /// `image_mse`, `observed_joint_rmse`, `object_iou`, …); `null` when the episode is too
    /// short for the scenario.
    pub fn score(
        &self,
        episode: &Episode,
        #[wasm_bindgen(unchecked_param_type = "string")] scenario: JsValue,
        #[wasm_bindgen(js_name = observations, unchecked_param_type = "number")] count: JsValue,
        #[wasm_bindgen(js_name = blend, unchecked_param_type = "number")] blend_value: JsValue,
    ) -> Result<JsValue, JsError> {
        let scenario: Scenario = choice(&scenario, "scenario", "\"interp\" or \"extrap\"")?;
        let (observations, blend) = (observations(&count)?, blend(&blend_value)?);
        let scores = score_sequence(
            &self.inner,
            episode.sequence(),
            "",
            scenario,
            observations,
            blend,
            None,
        )?;
        let Some(scores) = scores else {
            return Ok(JsValue::NULL);
        };
        let serializer = serde_wasm_bindgen::Serializer::json_compatible();
        let value = ScoreValue {
            model: scores.model.finish(),
            baseline: scores.baseline.finish(),
        };
        value
            .serialize(&serializer)
            .map_err(|e| JsError::new(&e.to_string()))
    }

    /// The imitation benchmark on one demonstration (what `dmbn imitate` does per sequence):
    /// the model observes `episode` (an episode of `action`, `"grasp"` or `"move"`) as `task`
    /// asks — `"frames"`: `observations` evenly spaced steps, the arm performs the whole
    /// predicted trajectory; `"finish"`: the first 30% at 3 steps, performed as recorded, then
    /// the prediction — with `blend` (1 = frames only, `"frames"`' default; `"finish"` uses 0.5
    /// in `dmbn imitate`), and the simulated arm performs the predicted joint means with the
    /// object where the episode had it. Returns an `Imitation`, `undefined` when the episode
    /// is too short for the task. Throws on bad arguments.
    pub fn imitate(
        &self,
        episode: &Episode,
        #[wasm_bindgen(js_name = action, unchecked_param_type = "string")] action_value: JsValue,
        #[wasm_bindgen(unchecked_param_type = "string")] task: JsValue,
        #[wasm_bindgen(js_name = observations, unchecked_param_type = "number")] count: JsValue,
        #[wasm_bindgen(js_name = blend, unchecked_param_type = "number")] blend_value: JsValue,
    ) -> Result<Option<Imitation>, JsError> {
        let action = action(&action_value)?;
        let task: Task = choice(&task, "task", "\"frames\" or \"finish\"")?;
        let (observations, blend) = (observations(&count)?, blend(&blend_value)?);
        let imitation = imitate::imitate(
            &self.inner,
            episode.sequence(),
            action,
            task,
            observations,
            blend,
        )?;
        Ok(imitation.map(Imitation::from))
    }
}

/// What `Model.score` returns.
#[derive(Serialize)]
struct ScoreValue {
    model: Quality,
    baseline: Quality,
}

impl ModelHandle {
    /// Fails unless this model encoded `contexts`.
    fn check_contexts(&self, contexts: &Contexts) -> Result<(), JsError> {
        if contexts.model != self.id {
            return Err(JsError::new(
                "these contexts were encoded by another model: encode the observations with this one",
            ));
        }
        Ok(())
    }

    /// The observations of `predict`, `encode` and `encodeContexts` from their JS arguments.
    fn observations(
        &self,
        frames: &JsValue,
        joints: &JsValue,
        times: &JsValue,
    ) -> Result<Observations, JsError> {
        Ok(Observations {
            image_size: self.image_size(),
            frames: bytes(frames, "frames")?,
            joints: floats(joints, "joints")?,
            times: floats(times, "times")?,
        })
    }
}

/// The predicted Gaussian at each target time (from `Model.predict` or `Model.decode`), copied
/// out as typed arrays.
#[wasm_bindgen]
pub struct Prediction {
    inner: SequencePrediction,
}

impl Prediction {
    /// The prediction, for Rust callers.
    pub fn inner(&self) -> &SequencePrediction {
        &self.inner
    }

    /// `k` as a target index of this prediction.
    fn check(&self, k: &JsValue) -> Result<usize, JsError> {
        let k = index(k, "k")?;
        if k < self.inner.len() {
            Ok(k)
        } else {
            Err(JsError::new(&format!(
                "target index {k} is out of range: the prediction has {} targets",
                self.inner.len()
            )))
        }
    }
}

#[wasm_bindgen]
impl Prediction {
    /// Number of target times T.
    #[wasm_bindgen(getter, js_name = len)]
    pub fn steps(&self) -> usize {
        self.inner.len()
    }

    /// Mean frames, `Float32Array(T × S × S × 3)`, RGB in [0, 1].
    #[wasm_bindgen(js_name = imageMean)]
    pub fn image_mean(&self) -> Vec<f32> {
        self.inner.image_mean.clone()
    }

    /// σ of every pixel channel, `Float32Array(T × S × S × 3)`.
    #[wasm_bindgen(js_name = imageSigma)]
    pub fn image_sigma(&self) -> Vec<f32> {
        self.inner.image_sigma.clone()
    }

    /// Mean joints, `Float32Array(T × D)`, in the data's units (radians, gripper).
    #[wasm_bindgen(js_name = jointMean)]
    pub fn joint_mean(&self) -> Vec<f32> {
        self.inner.joint_mean.clone()
    }

    /// σ of every joint, `Float32Array(T × D)`.
    #[wasm_bindgen(js_name = jointSigma)]
    pub fn joint_sigma(&self) -> Vec<f32> {
        self.inner.joint_sigma.clone()
    }

    /// Every mean frame as RGB bytes, `Uint8Array(T × S × S × 3)`.
    #[wasm_bindgen(js_name = meanFrames)]
    pub fn mean_frames(&self) -> Vec<u8> {
        self.inner.mean_frames()
    }

    /// σ of every pixel, `Float32Array(T × S × S)`: the mean over its 3 channels, what the σ
    /// heat maps show (`heatMap`, `sigmaMap`).
    #[wasm_bindgen(js_name = pixelSigma)]
    pub fn pixel_sigma(&self) -> Vec<f32> {
        self.inner.pixel_sigma()
    }

    /// Mean frame `k` as RGB bytes, `Uint8Array(S × S × 3)`.
    #[wasm_bindgen(js_name = meanFrame)]
    pub fn mean_frame(
        &self,
        #[wasm_bindgen(unchecked_param_type = "number")] k: JsValue,
    ) -> Result<Vec<u8>, JsError> {
        let k = self.check(&k)?;
        Ok(self.inner.mean_frame(k))
    }

    /// σ of frame `k` as an RGB heat map, `Uint8Array(S × S × 3)`; `scale` is the σ shown as
    /// full yellow (pass `maxImageSigma` to compare frames).
    #[wasm_bindgen(js_name = sigmaMap)]
    pub fn sigma_map(
        &self,
        #[wasm_bindgen(unchecked_param_type = "number")] k: JsValue,
        #[wasm_bindgen(unchecked_param_type = "number")] scale: JsValue,
    ) -> Result<Vec<u8>, JsError> {
        let k = self.check(&k)?;
        let scale = argument::number(&scale, "scale", 0.0, f64::MAX)? as f32;
        Ok(self.inner.sigma_map(k, scale))
    }

    /// The largest pixel σ of the prediction (of `pixelSigma`): the σ that `dmbn predict`
    /// shows as full yellow, the scale to pass to `sigmaMap` and `heatMap`.
    #[wasm_bindgen(getter, js_name = maxImageSigma)]
    pub fn max_image_sigma(&self) -> f32 {
        self.inner.max_image_sigma()
    }
}

/// `sample`'s arguments: the target times, the blend and the sampling (the CLI's defaults,
/// `samples` futures from `seed`).
fn sampling(
    target_times: &JsValue,
    blend_value: &JsValue,
    samples: &JsValue,
    seed_value: &JsValue,
) -> Result<(Vec<f32>, f32, Sampling), JsError> {
    let samples = argument::integer(samples, "samples", 1, Sampling::MAX_SAMPLES as u64)?;
    let sampling = Sampling {
        samples: samples as usize,
        seed: seed(seed_value)?,
        ..Sampling::default()
    };
    Ok((
        floats(target_times, "targetTimes")?,
        blend(blend_value)?,
        sampling,
    ))
}
