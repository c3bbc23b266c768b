//! The training and test sets of `dmbn probe`, and the checks and warnings its split deserves.
use std::path::{Path, PathBuf};

use dmbn::data::{id_list, Dataset, Sequence};
use dmbn::eval::split_warnings;
use dmbn::train::Split;

use crate::error::CliError;

/// How the test set is chosen: `--test-ids`, `--test-data` or `--test-fraction`.
pub enum TestSet<'a> {
    /// The ids A to B (inclusive) of `--data`.
    Ids(u32, u32),
    /// Every sequence of a second dataset.
    Data(&'a Path),
    /// The last fraction of the ids of `--data`.
    Fraction(f64),
}

impl TestSet<'_> {
    /// The flag's name, as `probe.json` records it.
    pub fn name(&self) -> &'static str {
        match self {
            TestSet::Ids(..) => "test-ids",
            TestSet::Data(_) => "test-data",
            TestSet::Fraction(_) => "test-fraction",
        }
    }
}

/// One side of the probe's split: sequences, the ids they come from, and where.
pub struct ProbeSet {
    pub sequences: Vec<Sequence>,
    pub ids: Vec<u32>,
    pub data: PathBuf,
}

impl ProbeSet {
    pub fn steps(&self) -> usize {
        self.sequences.iter().map(Sequence::len).sum()
    }
}

/// The dataset at `root`; errors name `flag`.
fn open(root: &Path, flag: &str) -> Result<Dataset, CliError> {
    Dataset::open(root).map_err(|e| CliError::Usage(format!("{flag}: {e}")))
}

/// The sequences of `dataset` whose id passes `keep` (frames at `size`), with their ids;
/// errors name `flag`.
fn read_all(
    dataset: &Dataset,
    size: usize,
    flag: &str,
    keep: impl Fn(u32) -> bool,
) -> Result<Vec<(u32, Sequence)>, CliError> {
    dataset
        .sequences()
        .iter()
        .filter(|r| keep(r.id))
        .map(|r| {
            let seq = dataset
                .read(r, Some(size as u32))
                .map_err(|e| CliError::Usage(format!("{flag}: {e}")))?;
            Ok((r.id, seq))
        })
        .collect()
}

fn set(seqs: Vec<(u32, Sequence)>, data: &Path) -> ProbeSet {
    let mut ids: Vec<u32> = seqs.iter().map(|(id, _)| *id).collect();
    ids.dedup();
    ProbeSet {
        sequences: seqs.into_iter().map(|(_, s)| s).collect(),
        ids,
        data: data.to_path_buf(),
    }
}

/// The training and test sets of `data` and `test` (frames at `size`), with clear errors
/// naming the flag.
pub fn probe_sets(
    data: &Path,
    test: &TestSet,
    size: usize,
) -> Result<(ProbeSet, ProbeSet), CliError> {
    match *test {
        TestSet::Ids(a, b) => {
            let dataset = open(data, "--data")?;
            let ids = dataset.ids();
            let in_range = |id: u32| (a..=b).contains(&id);
            if !ids.iter().any(|&id| in_range(id)) {
                return Err(CliError::Usage(format!(
                    "--test-ids {a}-{b}: {} holds no sequence with an id in {a}..={b} (its ids: \
                     {})",
                    data.display(),
                    id_list(&ids)
                )));
            }
            if ids.iter().all(|&id| in_range(id)) {
                return Err(CliError::Usage(format!(
                    "--test-ids {a}-{b}: every id of {} ({}) is in the test range, none is left \
                     to fit the heads on",
                    data.display(),
                    id_list(&ids)
                )));
            }
            let train = read_all(&dataset, size, "--data", |id| !in_range(id))?;
            let test = read_all(&dataset, size, "--data", in_range)?;
            Ok((set(train, data), set(test, data)))
        }
        TestSet::Data(dir) => {
            let train = read_all(&open(data, "--data")?, size, "--data", |_| true)?;
            let test = read_all(&open(dir, "--test-data")?, size, "--test-data", |_| true)?;
            Ok((set(train, data), set(test, dir)))
        }
        TestSet::Fraction(fraction) => {
            let split =
                Split::open(data, fraction).map_err(|e| CliError::Usage(format!("--data: {e}")))?;
            if split.val.is_empty() {
                return Err(CliError::Usage(format!(
                    "--test-fraction {fraction}: {} has too few ids for a test split (at least \
                     2 are needed; or give --test-data)",
                    data.display()
                )));
            }
            let dataset = open(data, "--data")?;
            let held = |id: u32| split.val_ids.contains(&id);
            let train = read_all(&dataset, size, "--data", |id| !held(id))?;
            let test = read_all(&dataset, size, "--data", held)?;
            Ok((set(train, data), set(test, data)))
        }
    }
}

/// Fails when either side holds no steps; else the warnings the split deserves: too small
/// ([`split_warnings`]), or `--test-data` naming `--data` itself.
pub fn check_split(
    train: &ProbeSet,
    test: &ProbeSet,
    by: &TestSet,
) -> Result<Vec<String>, CliError> {
    let test_flag = match by {
        TestSet::Data(_) => "--test-data",
        _ => "--data",
    };
    for (side, s, flag) in [("training", train, "--data"), ("test", test, test_flag)] {
        if s.steps() == 0 {
            return Err(CliError::Usage(format!(
                "{flag} {}: the {side} sequences hold no steps",
                s.data.display()
            )));
        }
    }
    let mut warnings = split_warnings(train.ids.len(), train.steps(), test.ids.len(), test.steps());
    if let TestSet::Data(_) = by {
        let same = |a: &Path, b: &Path| match (a.canonicalize(), b.canonicalize()) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        };
        if same(&train.data, &test.data) {
            warnings.push(format!(
                "--test-data {} is --data: the heads are tested on the steps they were fitted \
                 on, which measures memorisation, not generalisation",
                test.data.display()
            ));
        }
    }
    Ok(warnings)
}
