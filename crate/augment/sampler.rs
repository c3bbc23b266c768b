use rand::seq::index;
use rand::RngExt;
use rand_pcg::Pcg64;

use crate::data::{Normalization, Sequence};

use super::{Batch, JointTargets, Pick, Selection, Step, TimeWarpConfig};

/// How training batches are drawn (the original drew one sequence, 1-5 contexts and one
/// target per step; we batch several sequences and targets).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SamplerConfig {
    /// Sequences per batch (B).
    pub batch: usize,
    /// Largest context count; each sequence gets n ~ U{1..max_contexts} (N = max_contexts).
    pub max_contexts: usize,
    /// Targets per sequence (M): distinct from the contexts where the sequence allows, or,
    /// with `contexts_in_targets`, the contexts first, then other steps.
    pub targets: usize,
    /// Targets ⊇ contexts (the reference CNP's training): the model is also scored on
    /// reconstructing what it observed, the signal a CNP that underfits its contexts lacks.
    pub contexts_in_targets: bool,
    /// Joint-only targets per sequence, drawn uniformly from all its steps (see
    /// [`JointTargets`]); 0 for none.
    pub joint_targets: usize,
    /// Fraction of sequences observed through one modality only: c = 1 (frames) or c = 0
    /// (joints), half each; the rest draw c ~ U(0, 1). What the page's "images only" and
    /// "joints only" settings need a model to have seen; 0 keeps the paper's c ~ U(0, 1).
    pub single_modality: f32,
    /// Fraction of sequences observed only in a prefix of random length (10-90% of the
    /// sequence), their targets anywhere: forecasting the rest of an action from its start
    /// (the benchmark's `extrap`, the page's live mode), which contexts spread uniformly over
    /// a sequence almost never ask for (3 uniform steps all in the first 30%: 2.7%). 0 for none.
    pub prefix_contexts: f32,
    /// Time-warp every drawn sequence first (the paper's augmentation), or not.
    pub warp: Option<TimeWarpConfig>,
}

/// Draws context/target sets from sequences into [`Batch`]es. Both modalities are observed at
/// the same context steps; targets are steps that are not contexts.
#[derive(Debug, Clone, PartialEq)]
pub struct Sampler {
    pub config: SamplerConfig,
}

impl Sampler {
    pub fn new(config: SamplerConfig) -> Sampler {
        Sampler { config }
    }

    /// A batch of `config.batch` sequences picked uniformly from `pool`, with random context
    /// counts, steps and blending coefficients (c ~ U(0, 1), or one modality alone for a
    /// `single_modality` fraction).
    pub fn sample(&self, pool: &[Sequence], norm: &Normalization, rng: &mut Pcg64) -> Batch {
        self.sample_with_joints(pool, norm, rng).0
    }

    /// [`Sampler::sample`] with `config.joint_targets` joint-only targets per sequence (the
    /// random stream is the same as `sample`'s when there are none).
    pub fn sample_with_joints(
        &self,
        pool: &[Sequence],
        norm: &Normalization,
        rng: &mut Pcg64,
    ) -> (Batch, JointTargets) {
        let lengths: Vec<usize> = pool.iter().map(Sequence::len).collect();
        self.draw(&lengths, rng).fill(
            pool[0].image_size as usize,
            norm,
            |i| &pool[i].joints,
            |i, k| pool[i].frame(k),
        )
    }

    /// The random part of [`Sampler::sample_with_joints`] on a pool of sequences of
    /// `lengths` steps: the same draws from `rng`, no frame needed.
    pub fn draw(&self, lengths: &[usize], rng: &mut Pcg64) -> Selection {
        let cfg = self.config;
        let sequences: Vec<usize> = (0..cfg.batch)
            .map(|_| rng.random_range(0..lengths.len()))
            .collect();
        let picks = sequences
            .into_iter()
            .map(|sequence| {
                let recorded = lengths[sequence];
                // The recorded step behind each step of the (warped) sequence.
                let shown = match cfg.warp {
                    Some(warp) => warp.indices(recorded, rng),
                    None => (0..recorded).collect(),
                };
                let t = shown.len();
                let step = |k: usize| Step {
                    index: shown[k],
                    time: Sequence::phase(k, t),
                };
                let n = rng.random_range(1..=cfg.max_contexts.min(t.saturating_sub(1)).max(1));
                let prefix = cfg.prefix_contexts > 0.0 && rng.random::<f32>() < cfg.prefix_contexts;
                let steps = if prefix {
                    prefix_steps(rng, t, n, cfg.targets)
                } else {
                    index::sample(rng, t, (n + cfg.targets).min(t)).into_vec()
                };
                let (contexts, rest) = steps.split_at(n);
                let targets: Vec<usize> = if cfg.contexts_in_targets {
                    contexts
                        .iter()
                        .chain(rest)
                        .cycle()
                        .take(cfg.targets)
                        .copied()
                        .collect()
                } else {
                    // Short sequences: reuse non-context steps as targets.
                    (0..cfg.targets)
                        .map(|m| {
                            if rest.is_empty() {
                                contexts[0]
                            } else {
                                rest[m % rest.len()]
                            }
                        })
                        .collect()
                };
                let blend =
                    if cfg.single_modality > 0.0 && rng.random::<f32>() < cfg.single_modality {
                        if rng.random_bool(0.5) {
                            1.0
                        } else {
                            0.0
                        }
                    } else {
                        rng.random_range(0.0f32..=1.0)
                    };
                let joint_targets = (0..cfg.joint_targets)
                    .map(|_| step(rng.random_range(0..t)))
                    .collect();
                Pick {
                    sequence,
                    contexts: contexts.iter().map(|&k| step(k)).collect(),
                    targets: targets.into_iter().map(step).collect(),
                    joint_targets,
                    blend,
                }
            })
            .collect();
        Selection {
            contexts: cfg.max_contexts,
            targets: cfg.targets,
            joint_targets: cfg.joint_targets,
            picks,
        }
    }
}

/// `n` context steps within a prefix of 10-90% of a `t`-step sequence, then up to `targets`
/// other steps of the whole sequence (the layout `index::sample` gives: contexts first).
fn prefix_steps(rng: &mut Pcg64, t: usize, n: usize, targets: usize) -> Vec<usize> {
    let lo = (t / 10).max(n);
    let hi = (t * 9 / 10).max(lo);
    let len = rng.random_range(lo..=hi).min(t);
    let mut steps = index::sample(rng, len, n.min(len)).into_vec();
    let others: Vec<usize> = (0..t).filter(|k| !steps.contains(k)).collect();
    let picked = index::sample(rng, others.len(), targets.min(others.len()));
    steps.extend(picked.iter().map(|i| others[i]));
    steps
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::JOINTS;
    use rand::SeedableRng;

    /// A sequence whose frames count up byte by byte (for the layout test).
    fn seq(t: usize) -> Sequence {
        Sequence {
            image_size: 2,
            joints: (0..t).map(|k| [k as f32; 7]).collect(),
            endpoint: Some(vec![[0.0; 7]; t]),
            object: Some(vec![[0.0; 3]; t]),
            frames: (0..t * 12).map(|i| (i % 251) as u8).collect(),
        }
    }

    /// Sequence `id` of `t` steps, every value tagged with its sequence and step: joint j of
    /// step k is `1000·id + 10·k + j`, every byte of frame k is `100·id + k`.
    fn tagged(id: usize, t: usize) -> Sequence {
        assert!(100 * id + t <= 256, "frame tags fit a byte");
        Sequence {
            image_size: 2,
            joints: (0..t)
                .map(|k| std::array::from_fn::<f32, JOINTS, _>(|j| (1000 * id + 10 * k + j) as f32))
                .collect(),
            endpoint: Some(vec![[0.0; 7]; t]),
            object: Some(vec![[0.0; 3]; t]),
            frames: (0..t).flat_map(|k| [(100 * id + k) as u8; 12]).collect(),
        }
    }

    /// Statistics far from the identity (per column), so joints left unnormalised, or
    /// normalised with another column's statistics, decode to no step.
    fn norm() -> Normalization {
        Normalization {
            mean: vec![50.0, -20.0, 7.5, 300.0, 0.0, 1.0, -3.0],
            std: vec![4.0, 0.5, 10.0, 2.5, 8.0, 0.25, 3.0],
        }
    }

    /// The (sequence, step) a normalised joint row of `pool` comes from, checked against every
    /// joint of the row.
    fn joint_tag(pool: &[Sequence], joints: &[f32]) -> (usize, usize) {
        let row: [f32; 7] = joints.try_into().unwrap();
        let raw = norm().denormalize(&row);
        let tag = raw[0].round() as usize;
        let (id, k) = (tag / 1000, tag % 1000 / 10);
        assert!(id < pool.len() && k < pool[id].len(), "joints {raw:?}");
        for (j, &v) in raw.iter().enumerate() {
            let expected = (1000 * id + 10 * k + j) as f32;
            assert!((v - expected).abs() < 1e-2, "joint {j}: {v} at ({id}, {k})");
        }
        (id, k)
    }

    /// The (sequence, step) one context or target slot holds: its joints, its frame (every
    /// pixel of it) and its time must all name the same step of the same sequence.
    fn slot_tag(pool: &[Sequence], joints: &[f32], image: &[f32], time: f32) -> (usize, usize) {
        let (id, k) = joint_tag(pool, joints);
        let frame = (100 * id + k) as f32 / 255.0;
        assert!(
            image.iter().all(|&v| v == frame),
            "frame of ({id}, {k}): {image:?}"
        );
        assert_eq!(time, pool[id].times()[k], "time of ({id}, {k})");
        (id, k)
    }

    /// Every sequence of `batch` decoded: (the sequence, its context steps, its target steps).
    /// Checks that real contexts come first and the padding is zero, and that each sequence's
    /// contexts and targets all come from one sequence of `pool`.
    fn decode(pool: &[Sequence], batch: &Batch) -> Vec<(usize, Vec<usize>, Vec<usize>)> {
        let (n_max, m, s) = (batch.contexts, batch.targets, batch.image_size);
        let px = 3 * s * s;
        (0..batch.batch)
            .map(|b| {
                let mask = &batch.context_mask[b * n_max..(b + 1) * n_max];
                let n = mask.iter().filter(|&&v| v == 1.0).count();
                assert!((1..=n_max).contains(&n));
                assert!(mask[..n].iter().all(|&v| v == 1.0), "real contexts first");
                assert!(mask[n..].iter().all(|&v| v == 0.0), "then padding");
                let context = |i: usize| {
                    let slot = b * n_max + i;
                    slot_tag(
                        pool,
                        &batch.context_joints[slot * JOINTS..(slot + 1) * JOINTS],
                        &batch.context_images[slot * px..(slot + 1) * px],
                        batch.context_times[slot],
                    )
                };
                let target = |j: usize| {
                    let slot = b * m + j;
                    slot_tag(
                        pool,
                        &batch.target_joints[slot * JOINTS..(slot + 1) * JOINTS],
                        &batch.target_images[slot * px..(slot + 1) * px],
                        batch.target_times[slot],
                    )
                };
                let (contexts, targets): (Vec<_>, Vec<_>) =
                    ((0..n).map(context).collect(), (0..m).map(target).collect());
                let id = contexts[0].0;
                assert!(
                    contexts.iter().chain(&targets).all(|&(i, _)| i == id),
                    "sequence {b} mixes sequences: contexts {contexts:?}, targets {targets:?}"
                );
                for slot in b * n_max + n..(b + 1) * n_max {
                    assert!(batch.context_joints[slot * JOINTS..(slot + 1) * JOINTS]
                        .iter()
                        .chain(&batch.context_images[slot * px..(slot + 1) * px])
                        .chain([&batch.context_times[slot]])
                        .all(|&v| v == 0.0));
                }
                let steps = |v: Vec<(usize, usize)>| v.into_iter().map(|(_, k)| k).collect();
                (id, steps(contexts), steps(targets))
            })
            .collect()
    }

    fn distinct(steps: &[usize]) -> bool {
        steps
            .iter()
            .enumerate()
            .all(|(i, k)| !steps[..i].contains(k))
    }

    #[test]
    fn contexts_and_targets_are_distinct_steps_of_one_sequence() {
        let pool = vec![tagged(0, 20), tagged(1, 30)];
        let sampler = Sampler::new(SamplerConfig {
            batch: 16,
            max_contexts: 5,
            targets: 4,
            contexts_in_targets: false,
            joint_targets: 3,
            single_modality: 0.0,
            prefix_contexts: 0.0,
            warp: None,
        });
        let mut rng = Pcg64::seed_from_u64(1);
        let (batch, joint_targets) = sampler.sample_with_joints(&pool, &norm(), &mut rng);
        assert_eq!(batch.context_images.len(), 16 * 5 * 12);
        let decoded = decode(&pool, &batch);
        for (b, (id, contexts, targets)) in decoded.iter().enumerate() {
            assert!(distinct(contexts), "{contexts:?}");
            assert!(distinct(targets), "{targets:?}");
            assert!(
                targets.iter().all(|k| !contexts.contains(k)),
                "contexts {contexts:?}, targets {targets:?}"
            );
            assert!((0.0..=1.0).contains(&batch.blend[b]));
            // The joint-only targets are steps of the same sequence, at their times.
            for j in 0..3 {
                let slot = b * 3 + j;
                let (i, k) = joint_tag(
                    &pool,
                    &joint_targets.joints[slot * JOINTS..(slot + 1) * JOINTS],
                );
                assert_eq!(i, *id, "joint-only target {j} of sequence {b}");
                assert_eq!(joint_targets.times[slot], pool[i].times()[k]);
            }
        }
        for id in 0..2 {
            assert!(
                decoded.iter().any(|d| d.0 == id),
                "sequence {id} never drawn"
            );
        }
        let again = sampler.sample_with_joints(&pool, &norm(), &mut Pcg64::seed_from_u64(1));
        assert_eq!((batch, joint_targets), again, "deterministic for a seed");
    }

    #[test]
    fn contexts_lead_the_targets_when_asked() {
        let pool = vec![tagged(0, 20), tagged(1, 30)];
        let sampler = Sampler::new(SamplerConfig {
            batch: 16,
            max_contexts: 5,
            targets: 8,
            contexts_in_targets: true,
            joint_targets: 0,
            single_modality: 0.0,
            prefix_contexts: 0.0,
            warp: None,
        });
        let batch = sampler.sample(&pool, &norm(), &mut Pcg64::seed_from_u64(2));
        let decoded = decode(&pool, &batch);
        for (_, contexts, targets) in &decoded {
            let n = contexts.len();
            assert_eq!(&targets[..n], &contexts[..], "the contexts first");
            assert!(distinct(targets), "then other steps: {targets:?}");
        }
        for id in 0..2 {
            assert!(
                decoded.iter().any(|d| d.0 == id),
                "sequence {id} never drawn"
            );
        }
    }

    /// One sequence's batch: observe `contexts` with blend `blend`, predict `targets`.
    fn prediction(
        seq: &Sequence,
        contexts: &[usize],
        targets: &[usize],
        blend: f32,
        norm: &Normalization,
    ) -> Batch {
        let times = seq.times();
        let steps = |ks: &[usize]| {
            ks.iter()
                .map(|&index| Step {
                    index,
                    time: times[index],
                })
                .collect()
        };
        let selection = Selection {
            contexts: contexts.len(),
            targets: targets.len(),
            joint_targets: 0,
            picks: vec![Pick {
                sequence: 0,
                contexts: steps(contexts),
                targets: steps(targets),
                joint_targets: Vec::new(),
                blend,
            }],
        };
        let (image_size, joints) = (seq.image_size as usize, &seq.joints);
        selection
            .fill(image_size, norm, |_| joints, |_, k| seq.frame(k))
            .0
    }

    #[test]
    fn frames_are_channels_first_in_unit_range() {
        let s = seq(3);
        let batch = prediction(&s, &[1], &[0, 2], 0.5, &Normalization::identity(JOINTS));
        // Pixel 0 of frame 1 is bytes 12, 13, 14.
        assert_eq!(batch.context_images[0], 12.0 / 255.0);
        assert_eq!(batch.context_images[4], 13.0 / 255.0);
        assert_eq!(batch.context_images[8], 14.0 / 255.0);
        assert_eq!(batch.target_times, vec![0.0, 1.0]);
        assert_eq!(batch.context_times, vec![0.5]);
    }

    #[test]
    fn the_prediction_batch_holds_the_asked_steps() {
        let pool = vec![tagged(0, 5), tagged(1, 9)];
        let batch = prediction(&pool[1], &[7, 2], &[2, 0, 8], 0.25, &norm());
        assert_eq!(decode(&pool, &batch), vec![(1, vec![7, 2], vec![2, 0, 8])]);
        assert_eq!(batch.blend, vec![0.25]);
    }

    #[test]
    fn single_modality_draws_c_of_0_and_1() {
        let pool = vec![tagged(0, 20)];
        let sampler = Sampler::new(SamplerConfig {
            batch: 400,
            max_contexts: 3,
            targets: 2,
            contexts_in_targets: true,
            joint_targets: 0,
            single_modality: 0.5,
            prefix_contexts: 0.0,
            warp: None,
        });
        let batch = sampler.sample(&pool, &norm(), &mut Pcg64::seed_from_u64(3));
        decode(&pool, &batch);
        let count = |c: f32| batch.blend.iter().filter(|&&v| v == c).count();
        // About 100 each of c = 0 and c = 1, the other ~200 strictly inside.
        assert!((60..140).contains(&count(0.0)), "{}", count(0.0));
        assert!((60..140).contains(&count(1.0)), "{}", count(1.0));
        assert!(batch.blend.iter().all(|c| (0.0..=1.0).contains(c)));
    }

    #[test]
    fn prefix_contexts_observe_the_start_and_target_the_rest() {
        let pool = vec![tagged(0, 100), tagged(1, 100)];
        let sampler = Sampler::new(SamplerConfig {
            batch: 300,
            max_contexts: 5,
            targets: 8,
            contexts_in_targets: true,
            joint_targets: 0,
            single_modality: 0.0,
            prefix_contexts: 1.0,
            warp: None,
        });
        let batch = sampler.sample(&pool, &norm(), &mut Pcg64::seed_from_u64(4));
        let decoded = decode(&pool, &batch);
        let mut last_contexts = Vec::new();
        let mut future_targets = 0;
        let mut others = 0;
        for (_, contexts, targets) in &decoded {
            let n = contexts.len();
            let last = *contexts.iter().max().unwrap();
            assert!(
                last < 90,
                "a context at step {last}, past 90% of the sequence"
            );
            last_contexts.push(last);
            assert_eq!(
                &targets[..n],
                &contexts[..],
                "the contexts come first among the targets"
            );
            assert!(distinct(targets), "then other steps: {targets:?}");
            future_targets += targets[n..].iter().filter(|&&k| k > last).count();
            others += targets.len() - n;
        }
        for id in 0..2 {
            assert!(
                decoded.iter().any(|d| d.0 == id),
                "sequence {id} never drawn"
            );
        }
        // Prefixes of 10-90%: some end early, some late, and most targets lie ahead.
        assert!(last_contexts.iter().any(|&k| k < 30));
        assert!(last_contexts.iter().any(|&k| k > 60));
        assert!(
            future_targets * 2 > others,
            "{future_targets} of {others} targets ahead"
        );
    }

    /// The batches of a seed with every option that draws (warps, prefixes, single
    /// modalities, joint-only targets, both target layouts): a digest of every value, fixed
    /// so that the training stream stays the one runs were trained and resumed with.
    #[test]
    fn the_batches_of_a_seed_stay_the_same() {
        use sha2::{Digest, Sha256};
        let pool = vec![tagged(0, 20), tagged(1, 37), tagged(2, 9)];
        let mut h = Sha256::new();
        for (contexts_in_targets, freeze_fraction) in [(true, None), (false, Some([0.1, 0.6]))] {
            let sampler = Sampler::new(SamplerConfig {
                batch: 6,
                max_contexts: 5,
                targets: 8,
                contexts_in_targets,
                joint_targets: 7,
                single_modality: 0.3,
                prefix_contexts: 0.3,
                warp: Some(TimeWarpConfig {
                    probability: 0.8,
                    freeze_probability: 0.8,
                    freeze_fraction,
                    ..TimeWarpConfig::default()
                }),
            });
            let mut rng = Pcg64::seed_from_u64(11);
            for _ in 0..20 {
                let (b, j) = sampler.sample_with_joints(&pool, &norm(), &mut rng);
                for v in [
                    &b.context_images,
                    &b.context_joints,
                    &b.context_times,
                    &b.context_mask,
                    &b.target_images,
                    &b.target_joints,
                    &b.target_times,
                    &b.blend,
                    &j.times,
                    &j.joints,
                ]
                .into_iter()
                .flatten()
                {
                    h.update(v.to_le_bytes());
                }
            }
            h.update(rng.random::<u64>().to_le_bytes());
        }
        let digest: String = h.finalize().iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(
            digest,
            "6ba81877ceb96779bb453cf872d99d9564ac47a71ef3c257a5a4231bc63f0244"
        );
    }
}
