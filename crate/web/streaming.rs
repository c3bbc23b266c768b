use std::sync::atomic::{AtomicU32, Ordering};

use js_sys::{Float32Array, Object, Reflect, Uint8Array};
use wasm_bindgen::prelude::*;

use crate::model::Representation;
use crate::predict::{Observations, Predictor};

/// Tells models apart, so an encoding is only ever decoded by the model that made it.
static NEXT_ID: AtomicU32 = AtomicU32::new(1);

/// A trained model for progressive inference, as the demo page's worker runs it: encode the
/// observations once (`encode`), then decode target times in as many chunks as wanted
/// (`decode`), each returning plain typed arrays ready to transfer. Same [`Predictor`] as
/// `Model`; only the split differs (`Model.predict` encodes again on every call).
#[wasm_bindgen]
pub struct StreamingModel {
    inner: Predictor,
    id: u32,
}

/// Observations encoded by a `StreamingModel`: the blended representation r.
#[wasm_bindgen]
pub struct Encoding {
    inner: Representation,
    model: u32,
}

#[wasm_bindgen]
impl StreamingModel {
    /// Reads a model file (`Uint8Array`); throws on a truncated, corrupt or foreign file.
    #[wasm_bindgen(js_name = fromBytes)]
    pub fn from_bytes(bytes: &[u8]) -> Result<StreamingModel, JsError> {
        Ok(StreamingModel {
            inner: Predictor::from_bytes(bytes)?,
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
        })
    }

    /// `"dmbn"` or `"pte"`.
    #[wasm_bindgen(getter)]
    pub fn kind(&self) -> String {
        self.inner.model().kind().to_string()
    }

    /// Frame width and height the model reads and predicts.
    #[wasm_bindgen(getter, js_name = imageSize)]
    pub fn image_size(&self) -> usize {
        self.inner.model().image_size()
    }

    /// Encodes N observed steps, with the arguments of `Model.predict`: `frames` a
    /// `Uint8Array(N × S × S × 3)`, `joints` a `Float32Array(N × 7)`, `times` a
    /// `Float32Array(N)` in [0, 1], `blend` in [0, 1] (1 = images only, 0 = joints only).
    /// Throws on bad input.
    pub fn encode(
        &self,
        frames: Vec<u8>,
        joints: Vec<f32>,
        times: Vec<f32>,
        blend: f32,
    ) -> Result<Encoding, JsError> {
        let observations = Observations {
            image_size: self.image_size(),
            frames,
            joints,
            times,
        };
        Ok(Encoding {
            inner: self.inner.encode(&observations, blend)?,
            model: self.id,
        })
    }

    /// The prediction at `targetTimes` (a `Float32Array(M)` of finite phases) from `encoding`,
    /// as `{len, meanFrames, sigma, jointMean, jointSigma, maxSigma}`: `meanFrames` a
    /// `Uint8Array(M × S × S × 3)` of RGB mean frames, `sigma` a `Float32Array(M × S × S)` of
    /// per-pixel σ (the mean over the 3 channels, what the σ heat maps show), `maxSigma` its
    /// largest value, `jointMean` / `jointSigma` `Float32Array(M × 7)` in the episode's units.
    /// Throws when `encoding` comes from another model or a time is not finite.
    pub fn decode(
        &self,
        encoding: &Encoding,
        #[wasm_bindgen(js_name = targetTimes)] target_times: Vec<f32>,
    ) -> Result<JsValue, JsError> {
        if encoding.model != self.id {
            return Err(JsError::new(
                "this encoding was made by another model: encode the observations with this one",
            ));
        }
        let p = self.inner.decode(&encoding.inner, &target_times)?;
        let means: Vec<u8> = (0..p.len()).flat_map(|k| p.mean_frame(k)).collect();
        let sigma: Vec<f32> = p
            .image_sigma
            .chunks_exact(3)
            .map(|px| (px[0] + px[1] + px[2]) / 3.0)
            .collect();
        let max_sigma = sigma.iter().copied().fold(0.0, f32::max);
        let out = Object::new();
        let f32s = |v: &[f32]| JsValue::from(Float32Array::from(v));
        let fields = [
            ("len", JsValue::from(p.len() as u32)),
            ("meanFrames", Uint8Array::from(means.as_slice()).into()),
            ("sigma", f32s(&sigma)),
            ("maxSigma", JsValue::from(max_sigma)),
            ("jointMean", f32s(&p.joint_mean)),
            ("jointSigma", f32s(&p.joint_sigma)),
        ];
        for (key, value) in fields {
            Reflect::set(&out, &JsValue::from_str(key), &value)
                .map_err(|_| JsError::new("could not build the prediction object"))?;
        }
        Ok(out.into())
    }
}
