//! Whole datasets from the simulator, recorded on worker threads (native only).
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc;
use std::thread;

use super::{episode_with_arm, Action, Arm, SimError};
use crate::data::{DatasetWriter, Sequence};

/// One recorded episode, sent from a worker to the writing thread.
type Recorded = (u32, Action, u64, Result<Sequence, SimError>);

/// Records sequence `id` of every action for each id in `ids`, with seed `seed + id`
/// (wrapping), into a new dataset at `out`, so that (ids, seed, image size) reproduce it
/// exactly. `jobs` worker threads (at least 1, at most one per sequence) record, the calling
/// thread writes. The dataset is built by a [`DatasetWriter`] and renamed to `out` at the end:
/// a failed or interrupted run leaves no partial `out`. `progress(done, total)` runs on the
/// calling thread, once with 0 before the first sequence and once after each one written.
/// Returns where the dataset is. The arm is the UR5 ([`generate_with_arm`] picks another).
pub fn generate(
    out: &Path,
    ids: Range<u32>,
    seed: u64,
    actions: &[Action],
    image_size: u32,
    jobs: usize,
    progress: impl FnMut(usize, usize),
) -> Result<PathBuf, SimError> {
    let recording = (Arm::Ur5, actions);
    generate_with_arm(out, ids, seed, recording, image_size, jobs, progress)
}

/// [`generate`] with `arm` performing `actions`: its sequences have the arm's
/// [`width`](Arm::width) of joint values a step.
pub fn generate_with_arm(
    out: &Path,
    ids: Range<u32>,
    seed: u64,
    (arm, actions): (Arm, &[Action]),
    image_size: u32,
    jobs: usize,
    mut progress: impl FnMut(usize, usize),
) -> Result<PathBuf, SimError> {
    let mut seen = Vec::with_capacity(actions.len());
    for &a in actions {
        if seen.contains(&a) {
            return Err(SimError::DuplicateAction(a));
        }
        seen.push(a);
    }
    let tasks: Vec<(u32, Action)> = ids
        .flat_map(|id| actions.iter().map(move |&a| (id, a)))
        .collect();
    if tasks.is_empty() {
        return Err(SimError::NothingToGenerate);
    }
    let mut writer = DatasetWriter::create(out)?;
    let total = tasks.len();
    let workers = jobs.clamp(1, total);
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    progress(0, total);
    thread::scope(|s| {
        let (tx, rx) = mpsc::sync_channel::<Recorded>(workers * 2);
        for _ in 0..workers {
            let tx = tx.clone();
            let (tasks, next, stop) = (&tasks, &next, &stop);
            s.spawn(move || {
                while !stop.load(Ordering::Relaxed) {
                    let Some(&(id, action)) = tasks.get(next.fetch_add(1, Ordering::Relaxed))
                    else {
                        break;
                    };
                    let seed = seed.wrapping_add(u64::from(id));
                    if tx
                        .send((
                            id,
                            action,
                            seed,
                            episode_with_arm(arm, action, seed, image_size),
                        ))
                        .is_err()
                    {
                        break;
                    }
                }
            });
        }
        drop(tx);
        let outcome = write_all(rx, &mut writer, total, &mut progress);
        stop.store(true, Ordering::Relaxed);
        outcome
    })?;
    let written = writer.written();
    if written != total {
        return Err(SimError::Incomplete { written, total });
    }
    Ok(writer.finish()?)
}

/// Writes episodes as they arrive; returns at the first failure, dropping `rx` so that workers
/// blocked on a full channel see it closed and stop.
fn write_all(
    rx: mpsc::Receiver<Recorded>,
    writer: &mut DatasetWriter,
    total: usize,
    progress: &mut impl FnMut(usize, usize),
) -> Result<(), SimError> {
    for (id, action, seed, seq) in rx {
        let seq = seq.map_err(|source| SimError::Sequence {
            id,
            action,
            seed,
            source: Box::new(source),
        })?;
        writer.write(id, action.name(), &seq)?;
        progress(writer.written(), total);
    }
    Ok(())
}
