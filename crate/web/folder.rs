use std::path::{Component, Path};

use serde::Serialize;
use wasm_bindgen::prelude::*;

use super::Episode;
use crate::data::{read_sequence_from, Dataset, MemoryFiles};

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
    pub fn new(paths: Vec<String>) -> Result<Folder, JsError> {
        let files = MemoryFiles::new(&paths);
        let mut roots = paths.iter().filter_map(|p| first_part(p));
        let Some(root) = roots.next() else {
            return Err(JsError::new("the folder holds no file"));
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
    pub fn files_of(&self, id: u32, action: &str) -> Result<Vec<String>, JsError> {
        let dir = &self.dataset.find(id, action)?.dir;
        let names = crate::data::Files::files(&self.files, dir)?;
        Ok(names
            .iter()
            .map(|n| dir.join(n).display().to_string())
            .collect())
    }

    /// Hands over the bytes of the file at `path` (one of `filesOf`).
    pub fn put(&mut self, path: &str, bytes: Vec<u8>) {
        self.files.put(path, bytes);
    }

    /// Reads and validates sequence `id`/`action` from the bytes handed over, frames resized to
    /// `imageSize` (the model's) as `dmbn` does; the bytes are dropped afterwards. Throws the
    /// reader's error (a missing joint file, a malformed row, too few frames, not an image).
    pub fn read(
        &mut self,
        id: u32,
        action: &str,
        #[wasm_bindgen(js_name = imageSize)] image_size: u32,
    ) -> Result<Episode, JsError> {
        let result = self
            .dataset
            .find(id, action)
            .and_then(|s| read_sequence_from(&self.files, &s.dir, id, Some(image_size)));
        self.files.release();
        Ok(result?.into())
    }
}

/// The first part of a relative path (`data2020` of `data2020/0/grasp/0.png`).
fn first_part(path: &str) -> Option<&str> {
    Path::new(path).components().find_map(|c| match c {
        Component::Normal(s) => s.to_str(),
        _ => None,
    })
}
