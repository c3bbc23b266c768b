//! The paper's augmentation and evaluation sequences: warps are re-timings of the original
//! (same frames, in order, times in [0, 1]), lengths and freezes follow the settings, and
//! everything is deterministic with a seed; p permutes time stamps, f freezes frames.
use dmbn::augment::{AugmentError, EvalMode, EvalSequence, TimeWarpConfig};
use dmbn::data::Sequence;
use rand::SeedableRng;
use rand_pcg::Pcg64;

/// A sequence whose step k is recognisable: joints all k, frame bytes all k.
fn numbered(len: usize) -> Sequence {
    Sequence {
        image_size: 2,
        joints: (0..len).map(|k| [k as f32; 7]).collect(),
        endpoint: Some((0..len).map(|k| [k as f32; 7]).collect()),
        object: Some((0..len).map(|k| [k as f32; 3]).collect()),
        frames: (0..len).flat_map(|k| [k as u8; 12]).collect(),
    }
}

fn steps(seq: &Sequence) -> Vec<usize> {
    seq.joints.rows().map(|j| j[0] as usize).collect()
}

fn only_freeze(copies: usize) -> TimeWarpConfig {
    TimeWarpConfig {
        probability: 1.0,
        sections: [0, 0],
        freeze_probability: 1.0,
        freeze_length: [copies, copies],
        ..TimeWarpConfig::default()
    }
}

#[test]
fn warps_are_retimings_of_the_original() {
    let seq = numbered(80);
    let warp = TimeWarpConfig::default();
    let mut rng = Pcg64::seed_from_u64(5);
    let mut changed = 0;
    for _ in 0..200 {
        let warped = warp.apply(&seq, &mut rng);
        let s = steps(&warped);
        assert!(s.windows(2).all(|w| w[0] <= w[1]), "order kept: {s:?}");
        assert_eq!(
            (s[0], *s.last().unwrap()),
            (0, 79),
            "starts and ends as the original"
        );
        for (k, &step) in s.iter().enumerate() {
            assert_eq!(
                warped.frame(k),
                seq.frame(step),
                "frame {k} is original step {step}"
            );
            assert_eq!(
                warped.object.as_ref().unwrap()[k],
                seq.object.as_ref().unwrap()[step]
            );
        }
        let times = warped.times();
        assert!(times.windows(2).all(|w| w[0] < w[1]));
        assert_eq!((times[0], *times.last().unwrap()), (0.0, 1.0));
        changed += usize::from(s != (0..80).collect::<Vec<_>>());
    }
    assert!(
        changed > 120,
        "about 80% of sequences are warped, got {changed}/200"
    );
}

#[test]
fn lengths_and_freezes_follow_the_settings() {
    let seq = numbered(60);
    let mut rng = Pcg64::seed_from_u64(1);
    let frozen = only_freeze(7).apply(&seq, &mut rng);
    assert_eq!(frozen.len(), 67, "7 extra copies of one step");
    let s = steps(&frozen);
    let longest = s.chunk_by(|a, b| a == b).map(<[usize]>::len).max().unwrap();
    assert_eq!(longest, 8);

    let twice_as_fast = TimeWarpConfig {
        probability: 1.0,
        sections: [1, 1],
        section_fraction: [1.0, 1.0],
        speed: [2.0, 2.0],
        freeze_probability: 0.0,
        ..TimeWarpConfig::default()
    };
    let fast = twice_as_fast.apply(&seq, &mut rng);
    assert!((30..=32).contains(&fast.len()), "{}", fast.len());
    let half_speed = TimeWarpConfig {
        speed: [0.5, 0.5],
        ..twice_as_fast
    };
    let slow = half_speed.apply(&seq, &mut rng);
    assert!((118..=120).contains(&slow.len()), "{}", slow.len());

    // A freeze drawn as a fraction covers that fraction of the warped sequence.
    for fraction in [0.1, 0.5, 0.9] {
        let config = TimeWarpConfig {
            freeze_fraction: Some([fraction, fraction]),
            ..only_freeze(0)
        };
        let s = steps(&config.apply(&seq, &mut rng));
        let longest = s.chunk_by(|a, b| a == b).map(<[usize]>::len).max().unwrap();
        let covered = (longest - 1) as f64 / s.len() as f64;
        assert!((covered - fraction).abs() < 0.01, "{fraction}: {covered}");
    }

    let never = TimeWarpConfig {
        probability: 0.0,
        ..TimeWarpConfig::default()
    };
    assert_eq!(never.apply(&seq, &mut rng), seq);
}

#[test]
fn warps_are_deterministic_with_a_seed() {
    let seq = numbered(70);
    let warp = TimeWarpConfig::default();
    let a: Vec<Vec<usize>> = {
        let mut rng = Pcg64::seed_from_u64(9);
        (0..20).map(|_| warp.indices(70, &mut rng)).collect()
    };
    let mut rng = Pcg64::seed_from_u64(9);
    for indices in &a {
        assert_eq!(&steps(&warp.apply(&seq, &mut rng)), indices);
    }
}

#[test]
fn bad_warp_settings_are_named() {
    let bad = [
        (
            TimeWarpConfig {
                probability: 1.5,
                ..Default::default()
            },
            "probability",
        ),
        (
            TimeWarpConfig {
                speed: [0.0, 2.0],
                ..Default::default()
            },
            "speed",
        ),
        (
            TimeWarpConfig {
                speed: [2.0, 1.0],
                ..Default::default()
            },
            "speed",
        ),
        (
            TimeWarpConfig {
                section_fraction: [0.5, 1.5],
                ..Default::default()
            },
            "section_fraction",
        ),
        (
            TimeWarpConfig {
                freeze_length: [5, 2],
                ..Default::default()
            },
            "freeze_length",
        ),
        (
            TimeWarpConfig {
                freeze_fraction: Some([0.2, 1.0]),
                ..Default::default()
            },
            "freeze_fraction",
        ),
        (
            TimeWarpConfig {
                freeze_fraction: Some([0.5, 0.1]),
                ..Default::default()
            },
            "freeze_fraction",
        ),
    ];
    for (config, field) in bad {
        let err = config.validate().unwrap_err();
        assert!(
            matches!(&err, AugmentError::TimeWarp { field: f, .. } if *f == field),
            "{err}"
        );
        assert!(err.to_string().starts_with(field), "{err}");
    }
    assert!(TimeWarpConfig::default().validate().is_ok());
}

#[test]
fn p_permutes_the_time_stamps_and_keeps_the_frames() {
    let seq = numbered(40);
    let mut rng = Pcg64::seed_from_u64(3);
    let p = EvalSequence::build(EvalMode::Permuted, &seq, None, &mut rng);
    assert_eq!(p.sequence, seq);
    assert_ne!(p.times, seq.times());
    let mut sorted = p.times.clone();
    sorted.sort_by(f32::total_cmp);
    assert_eq!(sorted, seq.times());
    let t = EvalSequence::build(EvalMode::Unchanged, &seq, None, &mut rng);
    assert_eq!((t.sequence, t.times), (seq.clone(), seq.times()));
}

#[test]
fn f_freezes_a_section_or_the_whole_sequence() {
    let seq = numbered(30);
    let mut rng = Pcg64::seed_from_u64(3);
    let whole = EvalSequence::build(EvalMode::Frozen, &seq, None, &mut rng);
    assert_eq!(steps(&whole.sequence), vec![0; 30]);
    assert_eq!(whole.times, seq.times(), "time keeps running");
    let section = EvalSequence::frozen(&seq, 10, 20);
    let s = steps(&section.sequence);
    assert_eq!(&s[..10], &(0..10).collect::<Vec<_>>()[..]);
    assert_eq!(&s[10..20], &[10; 10]);
    assert_eq!(&s[20..], &(20..30).collect::<Vec<_>>()[..]);
    assert_eq!(section.sequence.frame(15), seq.frame(10));
    assert_eq!(
        steps(&EvalSequence::frozen(&seq, 25, 99).sequence)[29],
        25,
        "clamped"
    );
    assert_eq!("f".parse::<EvalMode>().unwrap(), EvalMode::Frozen);
    let err = "x".parse::<EvalMode>().unwrap_err();
    assert_eq!(err, AugmentError::Mode { found: "x".into() });
    assert!(err.to_string().contains("t, p or f"), "{err}");
}
