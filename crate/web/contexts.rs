use wasm_bindgen::prelude::*;

use super::argument;

use crate::model::EncodedContexts;

/// Observations encoded one by one by `Model.encodeContexts`, not yet aggregated, with the
/// model that made them (an id): join sets with `cat`, keep some with `select`, and turn a set
/// into an `Encoding` with `Model.represent`. The page's workers keep them per step, so that a
/// new observation is the only one encoded.
#[wasm_bindgen]
pub struct Contexts {
    pub(super) inner: EncodedContexts,
    pub(super) model: u32,
}

#[wasm_bindgen]
impl Contexts {
    /// N: the observations in the set.
    #[wasm_bindgen(getter)]
    pub fn len(&self) -> usize {
        self.inner.len()
    }

    /// Never true: every set holds an observation.
    #[wasm_bindgen(js_name = isEmpty)]
    pub fn is_empty(&self) -> bool {
        self.inner.is_empty()
    }

    /// A new set: this one's observations, then `other`'s. Throws when another model encoded
    /// `other`.
    pub fn cat(&self, other: &Contexts) -> Result<Contexts, JsError> {
        if other.model != self.model {
            return Err(JsError::new(
                "these contexts were encoded by another model: encode both with the same one",
            ));
        }
        Ok(Contexts {
            inner: self.inner.cat(&other.inner)?,
            model: self.model,
        })
    }

    /// A new set of the observations at `indices` (a `Uint32Array`, in that order). Throws on
    /// no index or one past the set.
    pub fn select(
        &self,
        #[wasm_bindgen(unchecked_param_type = "Uint32Array")] indices: JsValue,
    ) -> Result<Contexts, JsError> {
        let indices = argument::indices(&indices, "indices")?;
        Ok(Contexts {
            inner: self.inner.select(&indices)?,
            model: self.model,
        })
    }
}
