use std::path::PathBuf;

/// Where one sequence of a [`Dataset`](super::Dataset) lives: listed cheaply by
/// `Dataset::open`, read on demand, so a whole dataset never has to sit in memory.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct SequenceRef {
    /// The numeric id folder (also the suffix of the text files' names).
    pub id: u32,
    /// The action folder name, e.g. `grasp` or `move`.
    pub action: String,
    /// `<root>/<id>/<action>`.
    pub dir: PathBuf,
}
