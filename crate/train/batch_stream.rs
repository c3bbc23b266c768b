use std::sync::mpsc::{sync_channel, Receiver};
use std::thread::JoinHandle;

use rand_pcg::Pcg64;

use crate::augment::{Batch, JointTargets, Sampler};
use crate::data::{DataError, Normalization};

use super::{SequenceStore, TrainError};

/// Batches drawn ahead of the training step.
const AHEAD: usize = 1;

/// A training batch with the random stream's state after drawing it: what a checkpoint taken
/// after its step records, so that `--resume` draws the same next batch.
#[derive(Debug)]
pub(crate) struct Drawn {
    pub batch: Batch,
    pub joint_targets: JointTargets,
    pub rng: Pcg64,
}

/// The training batches of a run, drawn and read on a worker thread while the model trains
/// on the previous one: the batches [`Sampler::sample_with_joints`] draws from the same
/// random stream, with the frames read from disk ([`SequenceStore`]). The worker stays at most
/// `AHEAD` + 1 batches ahead; it stops at the first unreadable file, which
/// [`BatchStream::next`] reports, and when the stream is dropped.
pub(crate) struct BatchStream {
    receiver: Option<Receiver<Result<Drawn, DataError>>>,
    worker: Option<JoinHandle<()>>,
}

impl BatchStream {
    /// Start drawing from `rng`'s state with `sampler`, joints normalised with `norm`.
    pub fn spawn(
        mut store: SequenceStore,
        sampler: Sampler,
        norm: Normalization,
        mut rng: Pcg64,
    ) -> Result<BatchStream, TrainError> {
        let (sender, receiver) = sync_channel(AHEAD);
        let lengths = store.lengths();
        let worker = std::thread::Builder::new()
            .name("dmbn-batches".into())
            .spawn(move || loop {
                let selection = sampler.draw(&lengths, &mut rng);
                let drawn = store
                    .batch(&selection, &norm)
                    .map(|(batch, joint_targets)| Drawn {
                        batch,
                        joint_targets,
                        rng: rng.clone(),
                    });
                let failed = drawn.is_err();
                if sender.send(drawn).is_err() || failed {
                    break;
                }
            })
            .map_err(|e| TrainError::Batches {
                message: format!("cannot start the thread that reads them: {e}"),
            })?;
        Ok(BatchStream {
            receiver: Some(receiver),
            worker: Some(worker),
        })
    }

    /// The next batch: an error naming the file when one could not be read.
    pub fn next(&mut self) -> Result<Drawn, TrainError> {
        let received = self.receiver.as_ref().map(Receiver::recv);
        match received {
            Some(Ok(drawn)) => Ok(drawn?),
            _ => Err(TrainError::Batches {
                message:
                    "the thread reading them has stopped (after an unreadable file, or a fault)"
                        .into(),
            }),
        }
    }
}

impl Drop for BatchStream {
    /// Ends the worker: with the receiver gone, its next send fails and it returns.
    fn drop(&mut self) {
        drop(self.receiver.take());
        if let Some(worker) = self.worker.take() {
            let _ = worker.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use rand::SeedableRng;

    use super::*;
    use crate::data::JOINTS;
    use crate::train::sequence_store::tests::{dataset, in_memory, sampler, STORED};

    #[test]
    fn streamed_batches_are_the_in_memory_sampler_s_bit_for_bit() {
        let tmp = tempfile::tempdir().unwrap();
        let refs = dataset(tmp.path());
        let pool = in_memory(&refs);
        // A cache of a few frames: most are decoded again, some come from it.
        let store =
            SequenceStore::open(refs, STORED / 2, 3000, None, (JOINTS, "the first sequence"))
                .unwrap();
        let norm = Normalization::fit(JOINTS, store.joints());
        let mut reference = Pcg64::seed_from_u64(5);
        let mut stream =
            BatchStream::spawn(store, sampler(), norm.clone(), reference.clone()).unwrap();
        for i in 0..30 {
            let drawn = stream.next().unwrap();
            let (batch, joint_targets) = sampler().sample_with_joints(&pool, &norm, &mut reference);
            assert!(drawn.batch == batch, "batch {i}");
            assert!(drawn.joint_targets == joint_targets, "joint targets {i}");
            assert!(drawn.rng == reference, "the random stream after batch {i}");
        }
    }

    /// `spoil` applied to the dataset after two batches: the stream's next batches must come
    /// to an error (never a panic or a wait without end) naming the dataset's file, then say
    /// that it has stopped.
    fn fails_naming(spoil: impl Fn(&Path), says: &str) {
        let tmp = tempfile::tempdir().unwrap();
        let refs = dataset(tmp.path());
        let store =
            SequenceStore::open(refs, STORED / 2, 0, None, (JOINTS, "the first sequence")).unwrap();
        let norm = Normalization::fit(JOINTS, store.joints());
        let mut stream =
            BatchStream::spawn(store, sampler(), norm, Pcg64::seed_from_u64(9)).unwrap();
        for _ in 0..2 {
            stream.next().unwrap();
        }
        spoil(tmp.path());
        // The batches read ahead before the damage, then the error; on a thread, so that a
        // reader that never reports fails the test instead of stalling it.
        let (report, reported) = sync_channel(1);
        std::thread::spawn(move || {
            let error = (0..AHEAD + 2).find_map(|_| stream.next().err());
            let after = stream.next().err();
            let _ = report.send((error, after));
        });
        let (error, after) = reported
            .recv_timeout(std::time::Duration::from_secs(60))
            .expect("no error within 60 s: the batch reader hangs");
        let message = error.expect("the damaged dataset is noticed").to_string();
        let root = tmp.path().display().to_string();
        assert!(
            message.starts_with(&root) && message.contains(says),
            "{message}"
        );
        let after = after.expect("an error after the first").to_string();
        assert!(after.contains("has stopped"), "{after}");
    }

    #[test]
    fn a_frame_gone_bad_mid_run_is_an_error_naming_it() {
        fails_naming(
            |root| {
                for id in 0..4 {
                    let dir = root.join(id.to_string()).join("grasp");
                    for entry in std::fs::read_dir(&dir).unwrap() {
                        let path = entry.unwrap().path();
                        if path.extension().is_some_and(|e| e == "png") {
                            std::fs::write(path, b"not a png").unwrap();
                        }
                    }
                }
            },
            ".png: cannot decode frame",
        );
    }

    #[test]
    fn a_sequence_gone_mid_run_is_an_error_naming_its_folder() {
        fails_naming(
            |root| {
                for id in 0..4 {
                    std::fs::remove_dir_all(root.join(id.to_string())).unwrap();
                }
            },
            // Gone while a listing reads the folder: its frames go missing.
            "/grasp",
        );
    }
}
