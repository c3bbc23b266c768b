use std::collections::HashMap;
use std::sync::Arc;

use crate::augment::{Batch, JointTargets, Selection};
use crate::data::{
    camera_dir, read_frames, read_joints, read_sequence_from, DataError, Dataset, Disk, Joints,
    Normalization, Sequence, SequenceRef,
};

use super::FrameCache;

/// Sequences of a dataset as training reads them: their joints in memory (small: the sampler
/// needs the lengths, the normalisation all joints), their frames read from disk when a batch
/// holds them, through a [`FrameCache`] of bounded size. Memory does not grow with the number
/// of sequences beyond their joints.
pub(crate) struct SequenceStore {
    sequences: Vec<SequenceRef>,
    joints: Vec<Joints>,
    image_size: u32,
    camera: Option<String>,
    cache: FrameCache,
}

impl SequenceStore {
    /// The joints of `sequences` read (every one `width` values a step, as `reference`, the
    /// file they must agree with, says), their frames (`camera`'s, at `image_size` pixels)
    /// left on disk, up to `cache_bytes` of them to be kept once decoded.
    pub fn open(
        sequences: Vec<SequenceRef>,
        image_size: u32,
        cache_bytes: usize,
        camera: Option<&str>,
        (width, reference): (usize, &str),
    ) -> Result<SequenceStore, DataError> {
        let mut joints = Vec::with_capacity(sequences.len());
        for s in &sequences {
            let rows = read_joints(&Disk, &s.dir, s.id)?;
            Dataset::check_width(s, rows.width(), width, reference)?;
            joints.push(rows);
        }
        Ok(SequenceStore {
            sequences,
            joints,
            image_size,
            camera: camera.map(str::to_string),
            cache: FrameCache::new(cache_bytes),
        })
    }

    /// Number of sequences.
    pub fn len(&self) -> usize {
        self.sequences.len()
    }

    /// True when it holds no sequence.
    pub fn is_empty(&self) -> bool {
        self.sequences.is_empty()
    }

    /// Steps of each sequence: what the sampler draws from.
    pub fn lengths(&self) -> Vec<usize> {
        self.joints.iter().map(Joints::len).collect()
    }

    /// Every step's joints, sequence after sequence.
    pub fn joints(&self) -> impl Iterator<Item = &[f32]> {
        self.joints.iter().flat_map(Joints::rows)
    }

    /// Sequence `i` read whole (frames and all).
    pub fn read(&self, i: usize) -> Result<Sequence, DataError> {
        let s = &self.sequences[i];
        let camera = self.camera.as_deref();
        read_sequence_from(&Disk, &s.dir, s.id, camera, Some(self.image_size))
    }

    /// The batch `selection` (drawn from [`SequenceStore::lengths`]) describes, its frames
    /// taken from the cache or decoded, and cached; an unreadable frame is an error naming its
    /// file.
    pub fn batch(
        &mut self,
        selection: &Selection,
        norm: &Normalization,
    ) -> Result<(Batch, JointTargets), DataError> {
        let mut frames: HashMap<(usize, usize), Arc<[u8]>> = HashMap::new();
        for pick in &selection.picks {
            let i = pick.sequence;
            let mut missing = Vec::new();
            for k in pick.frame_steps() {
                if frames.contains_key(&(i, k)) {
                    continue;
                }
                match self.cache.get(i, k) {
                    Some(frame) => {
                        frames.insert((i, k), frame);
                    }
                    None => missing.push(k),
                }
            }
            if missing.is_empty() {
                continue;
            }
            let s = &self.sequences[i];
            let rows = self.joints[i].len();
            let dir = camera_dir(&s.dir, self.camera.as_deref());
            let decoded = read_frames(&Disk, &dir, rows, &missing, self.image_size)?;
            for (k, frame) in missing.into_iter().zip(decoded) {
                let frame: Arc<[u8]> = frame.into();
                self.cache.insert(i, k, frame.clone());
                frames.insert((i, k), frame);
            }
        }
        Ok(selection.fill(
            self.image_size as usize,
            norm,
            |i| &self.joints[i],
            |i, k| &frames[&(i, k)],
        ))
    }

    /// Bytes of decoded frames held.
    #[cfg(test)]
    pub fn cached_bytes(&self) -> usize {
        self.cache.bytes()
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use std::path::Path;

    use rand::SeedableRng;
    use rand_pcg::Pcg64;

    use super::*;
    use crate::augment::{Sampler, SamplerConfig, TimeWarpConfig};
    use crate::data::{read_sequence, write_sequence, Dataset, JOINTS};

    /// Frame size of [`dataset`]'s files; sequences are read at half of it (the reader's
    /// area average).
    pub const STORED: u32 = 16;

    /// A dataset at `root` of sequences of 9, 14, 23 and 31 steps (ids 0-3), every frame and
    /// joint different; returns its sequences.
    pub fn dataset(root: &Path) -> Vec<SequenceRef> {
        let mut state = 0x2545_f491_u32;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state
        };
        for (id, t) in [9usize, 14, 23, 31].into_iter().enumerate() {
            let px = (STORED * STORED * 3) as usize;
            let seq = Sequence {
                image_size: STORED,
                joints: (0..t)
                    .map(|_| {
                        std::array::from_fn::<f32, JOINTS, _>(|_| (next() % 1000) as f32 / 100.0)
                    })
                    .collect(),
                endpoint: Some(vec![[0.0; 7]; t]),
                object: Some(vec![[0.0; 3]; t]),
                frames: (0..t * px).map(|_| next() as u8).collect(),
            };
            write_sequence(root, id as u32, "grasp", &seq).unwrap();
        }
        Dataset::open(root).unwrap().sequences().to_vec()
    }

    /// The training sampler with every option that draws: warps, prefixes, single
    /// modalities, joint-only targets.
    pub fn sampler() -> Sampler {
        Sampler::new(SamplerConfig {
            batch: 3,
            max_contexts: 4,
            targets: 5,
            contexts_in_targets: true,
            joint_targets: 6,
            single_modality: 0.3,
            prefix_contexts: 0.3,
            warp: Some(TimeWarpConfig {
                probability: 0.8,
                freeze_probability: 0.8,
                ..TimeWarpConfig::default()
            }),
        })
    }

    /// The sequences of `refs` read whole, as training held them before it streamed.
    pub fn in_memory(refs: &[SequenceRef]) -> Vec<Sequence> {
        refs.iter()
            .map(|s| read_sequence(&s.dir, s.id, Some(STORED / 2)).unwrap())
            .collect()
    }

    #[test]
    fn the_cache_stays_within_its_bound_and_changes_no_batch() {
        let tmp = tempfile::tempdir().unwrap();
        let refs = dataset(tmp.path());
        let pool = in_memory(&refs);
        let frame = (STORED / 2 * STORED / 2 * 3) as usize;
        let bound = 7 * frame;
        let mut store = SequenceStore::open(
            refs,
            STORED / 2,
            bound,
            None,
            (JOINTS, "the first sequence"),
        )
        .unwrap();
        let norm = Normalization::fit(JOINTS, store.joints());
        let (sampler, mut rng) = (sampler(), Pcg64::seed_from_u64(7));
        let mut reference = rng.clone();
        let mut most = 0;
        for i in 0..40 {
            let selection = sampler.draw(&store.lengths(), &mut rng);
            let streamed = store.batch(&selection, &norm).unwrap();
            assert!(
                store.cached_bytes() <= bound,
                "batch {i}: {} bytes cached, the bound is {bound}",
                store.cached_bytes()
            );
            most = most.max(store.cached_bytes());
            let held = sampler.sample_with_joints(&pool, &norm, &mut reference);
            assert!(streamed == held, "batch {i} differs from the in-memory one");
        }
        assert_eq!(most, bound, "the cache is used up to its bound");
    }
}
