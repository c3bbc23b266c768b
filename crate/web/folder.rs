use std::path::{Component, Path};

use serde::Serialize;
use wasm_bindgen::prelude::*;

use super::argument::{bytes, image_size, integer, string, strings, wrong};
use super::Episode;
use crate::data::{read_sequence_from, Dataset, MemoryFiles, SequenceRef};

/// A folder in the DMBN layout that the user opened in the page: listed and read by the native
/// reader's code ([`Dataset::list`], [`read_sequence_from`]) on the files the browser hands
/// over, so the rules and the error messages (naming the file, relative to the folder, and the
/// line) are the tools'. Frames are decoded and resized here too, exactly as natively.
#[wasm_bindgen]
pub struct Folder {
    files: MemoryFiles,
    dataset: Dataset,
}

/// One sequence of a [`Folder`], as `Folder.sequences()` lists it.
#[derive(Serialize)]
struct SequenceName {
    id: u32,
    action: String,
}

#[wasm_bindgen]
impl Folder {
    /// `new Folder(paths)`: lists the sequences of the folder whose files have the relative
    /// paths `paths` (`data2020/0/grasp/0.jpeg`, …, as `File.webkitRelativePath` names them;
    /// all under one folder). Throws the reader's error: no sequence folders, an id folder
    /// without actions.
    #[wasm_bindgen(constructor)]
    pub fn new(
        #[wasm_bindgen(unchecked_param_type = "string[]")] paths: JsValue,
    ) -> Result<Folder, JsError> {
        let names = strings(&paths, "paths")?;
        let files = MemoryFiles::new(&names);
        let mut roots = names.iter().filter_map(|p| first_part(p));
        let Some(root) = roots.next() else {
            let expected = "the relative paths of the folder's files (the folder holds none)";
            return Err(wrong("paths", expected, &paths));
        };
        if let Some(other) = roots.find(|r| *r != root) {
            return Err(JsError::new(&format!(
                "expected the files of one folder, found {root}/ and {other}/"
            )));
        }
        let dataset = Dataset::list(&files, root)?;
        Ok(Folder { files, dataset })
    }

    /// The folder's name.
    #[wasm_bindgen(getter)]
    pub fn root(&self) -> String {
        self.dataset.root().display().to_string()
    }

    /// `[{id, action}]`: every sequence, by id then action.
    pub fn sequences(&self) -> Result<JsValue, JsError> {
        let list: Vec<SequenceName> = self
            .dataset
            .sequences()
            .iter()
            .map(|s| SequenceName {
                id: s.id,
                action: s.action.clone(),
            })
            .collect();
        serde_wasm_bindgen::to_value(&list).map_err(|e| JsError::new(&e.to_string()))
    }

    /// Paths of the files sequence `id`/`action` is read from: hand their bytes over with
    /// `put` before `read`. Throws when the folder has no such sequence.
    #[wasm_bindgen(js_name = filesOf)]
    pub fn files_of(
        &self,
        #[wasm_bindgen(unchecked_param_type = "number")] id: JsValue,
        #[wasm_bindgen(unchecked_param_type = "string")] action: JsValue,
    ) -> Result<Vec<String>, JsError> {
        let dir = &self.sequence(&id, &action)?.dir;
        let names = crate::data::Files::files(&self.files, dir)?;
        Ok(names
            .iter()
            .map(|n| dir.join(n).display().to_string())
            .collect())
    }

    /// Hands over the bytes of the file at `path` (one of `filesOf`). Throws for a path that
    /// is not one of the folder's files.
    pub fn put(
        &mut self,
        #[wasm_bindgen(unchecked_param_type = "string")] path: JsValue,
        #[wasm_bindgen(js_name = bytes, unchecked_param_type = "Uint8Array")] content: JsValue,
    ) -> Result<(), JsError> {
        let name = string(&path, "path")?;
        if !self.files.contains(&name) {
            return Err(wrong(
                "path",
                "a file of this folder (one of filesOf's)",
                &path,
            ));
        }
        self.files.put(&name, bytes(&content, "bytes")?);
        Ok(())
    }

    /// Reads and validates sequence `id`/`action` from the bytes handed over, frames resized to
    /// `imageSize` (the model's) as `dmbn` does; the bytes are dropped afterwards. Throws the
    /// reader's error (a missing joint file, a malformed row, too few frames, not an image).
    pub fn read(
        &mut self,
        #[wasm_bindgen(unchecked_param_type = "number")] id: JsValue,
        #[wasm_bindgen(unchecked_param_type = "string")] action: JsValue,
        #[wasm_bindgen(js_name = imageSize, unchecked_param_type = "number")] size: JsValue,
    ) -> Result<Episode, JsError> {
        let size = image_size(&size)?;
        let result = self.sequence(&id, &action).and_then(|s| {
            read_sequence_from(&self.files, &s.dir, s.id, None, Some(size)).map_err(JsError::from)
        });
        self.files.release();
        Ok(result?.into())
    }
}

impl Folder {
    /// The sequence `id`/`action` of the folder, from JS arguments: an integer id and one of
    /// the folder's actions (checked first, so a wrong one is named, not quoted at length).
    fn sequence(&self, id: &JsValue, action: &JsValue) -> Result<&SequenceRef, JsError> {
        let id = integer(id, "id", 0, u64::from(u32::MAX))? as u32;
        let name = string(action, "action")?;
        let actions = self.dataset.actions();
        if !actions.contains(&name) {
            let expected = format!("one of the folder's actions ({})", actions.join(", "));
            return Err(wrong("action", &expected, action));
        }
        Ok(self.dataset.find(id, &name)?)
    }
}

/// The first part of a relative path (`data2020` of `data2020/0/grasp/0.png`).
fn first_part(path: &str) -> Option<&str> {
    Path::new(path).components().find_map(|c| match c {
        Component::Normal(s) => s.to_str(),
        _ => None,
    })
}
