//! Dataset reading and writing on small hand-made fixtures (no simulator involved), plus a
//! check of the original DMBN dataset when it is available.
mod support;

use std::fs;
use std::path::{Path, PathBuf};

use dmbn::data::{
    joint_path, object_path, read_sequence, read_sequence_from, write_sequence, DataError, Dataset,
    DatasetWriter, Joints, MemoryFiles, Sequence, Summary,
};
use image::codecs::jpeg::JpegEncoder;
use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder};

/// A small sequence with awkward float values (tiny, negative, many digits) and frames whose
/// bytes depend on step, position and `salt`.
fn fixture(steps: usize, size: u32, salt: u32) -> Sequence {
    let joints = (0..steps)
        .map(|k| {
            let k = k as f32;
            [
                -0.066_302_45 + 0.1 * k,
                0.197_028_13,
                -1.740_841_4 * k,
                1e-7 * (salt as f32 + 1.0),
                -9.946_174e-5,
                3.0,
                7.013_37e-5 * k,
            ]
        })
        .collect();
    let endpoint = (0..steps)
        .map(|k| {
            [
                0.01 * k as f32,
                0.049_728_677,
                1.296_702,
                0.0,
                -3.059_117_8,
                1e-30,
                0.5,
            ]
        })
        .collect();
    let object = (0..steps)
        .map(|k| [3.229_036e-7, -1.924_005e-7 * k as f32, 0.914_839_2])
        .collect();
    let mut frames = Vec::new();
    for k in 0..steps as u32 {
        for y in 0..size {
            for x in 0..size {
                frames.push((x * 7 + k * 31 + salt) as u8);
                frames.push((y * 5 + k * 11) as u8);
                frames.push((x ^ y ^ salt) as u8);
            }
        }
    }
    Sequence {
        image_size: size,
        joints,
        endpoint: Some(endpoint),
        object: Some(object),
        frames,
    }
}

/// A sequence with frames of one flat colour per step (survives JPEG nearly unchanged).
fn flat_fixture(steps: usize, size: u32) -> Sequence {
    let mut seq = fixture(steps, size, 0);
    seq.frames = (0..steps)
        .flat_map(|k| {
            let px = [40 + 50 * k as u8, 120, 200 - 30 * k as u8];
            std::iter::repeat_n(px, (size * size) as usize).flatten()
        })
        .collect();
    seq
}

fn write_png(path: &Path, rgb: &[u8], w: u32, h: u32) {
    let mut png = Vec::new();
    PngEncoder::new(&mut png)
        .write_image(rgb, w, h, ExtendedColorType::Rgb8)
        .unwrap();
    fs::write(path, png).unwrap();
}

/// Write `seq` as sequence `id` of `grasp` under a fresh temporary root.
fn written(id: u32, seq: &Sequence) -> (tempfile::TempDir, PathBuf) {
    let root = tempfile::tempdir().unwrap();
    let dir = write_sequence(root.path(), id, "grasp", seq).unwrap();
    (root, dir)
}

/// Assert `err`'s message contains every piece, printing it on failure.
fn assert_message(err: &DataError, pieces: &[&str]) {
    let msg = err.to_string();
    for p in pieces {
        assert!(msg.contains(p), "message {msg:?} lacks {p:?}");
    }
}

fn replace_line(path: &Path, line: usize, text: &str) {
    let content = fs::read_to_string(path).unwrap();
    let mut lines: Vec<String> = content.lines().map(String::from).collect();
    lines[line - 1] = text.to_string();
    fs::write(path, lines.join("\n") + "\n").unwrap();
}

#[test]
fn round_trip_is_exact() {
    let seq = fixture(5, 16, 3);
    let (_root, dir) = written(3, &seq);
    let back = read_sequence(&dir, 3, None).unwrap();
    assert_eq!(back, seq);
    assert_eq!(back.digest(), seq.digest());
    // frames are PNGs and the text uses Rust's shortest `{}` formatting
    assert!(dir.join("4.png").is_file());
    let joints = fs::read_to_string(joint_path(&dir, 3)).unwrap();
    let first = joints.lines().next().unwrap();
    assert_eq!(
        first,
        "-0.06630245 0.19702813 -0 0.0000004 -0.00009946174 3 0"
    );
}

#[test]
fn writing_is_deterministic() {
    let seq = fixture(3, 8, 1);
    let (_a, dir_a) = written(0, &seq);
    let (_b, dir_b) = written(0, &seq);
    let mut names: Vec<_> = fs::read_dir(&dir_a)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    names.sort();
    assert_eq!(
        names.len(),
        6,
        "3 frames + 3 text files, no temporaries: {names:?}"
    );
    for name in names {
        assert_eq!(
            fs::read(dir_a.join(&name)).unwrap(),
            fs::read(dir_b.join(&name)).unwrap(),
            "{name:?} differs"
        );
    }
}

#[test]
fn jpeg_frames_are_read() {
    let seq = flat_fixture(3, 16);
    let (_root, dir) = written(1, &seq);
    for k in 0..3 {
        fs::remove_file(dir.join(format!("{k}.png"))).unwrap();
        let mut jpeg = Vec::new();
        JpegEncoder::new_with_quality(&mut jpeg, 95)
            .write_image(seq.frame(k), 16, 16, ExtendedColorType::Rgb8)
            .unwrap();
        fs::write(dir.join(format!("{k}.jpeg")), &jpeg).unwrap();
    }
    let back = read_sequence(&dir, 1, None).unwrap();
    assert_eq!(back.joints, seq.joints);
    assert_eq!(back.image_size, 16);
    assert_eq!(back.frames.len(), seq.frames.len());
    let worst = back
        .frames
        .iter()
        .zip(&seq.frames)
        .map(|(a, b)| a.abs_diff(*b))
        .max()
        .unwrap();
    assert!(worst <= 4, "JPEG frames off by up to {worst}");
}

#[test]
fn extra_frames_are_ignored() {
    let seq = fixture(3, 8, 2);
    let (_root, dir) = written(2, &seq);
    fs::copy(dir.join("0.png"), dir.join("3.png")).unwrap();
    fs::write(dir.join("4.jpeg"), b"not a jpeg, never decoded").unwrap();
    fs::write(dir.join("notes.txt"), b"unrelated").unwrap();
    assert_eq!(read_sequence(&dir, 2, None).unwrap(), seq);
}

#[test]
fn frames_are_resized_by_area_average() {
    let seq = fixture(2, 128, 5);
    let (_root, dir) = written(0, &seq);
    let small = read_sequence(&dir, 0, Some(64)).unwrap();
    assert_eq!(small.image_size, 64);
    assert_eq!(small.joints, seq.joints);
    assert_eq!(small.frames.len(), 2 * 64 * 64 * 3);
    for k in 0..2 {
        let big = seq.frame(k);
        let px = |x: usize, y: usize, c: usize| u32::from(big[(y * 128 + x) * 3 + c]);
        for y in 0..64 {
            for x in 0..64 {
                for c in 0..3 {
                    let sum = px(2 * x, 2 * y, c)
                        + px(2 * x + 1, 2 * y, c)
                        + px(2 * x, 2 * y + 1, c)
                        + px(2 * x + 1, 2 * y + 1, c);
                    let got = small.frame(k)[(y * 64 + x) * 3 + c];
                    assert_eq!(u32::from(got), (sum + 2) / 4, "frame {k} ({x}, {y}) {c}");
                }
            }
        }
    }
    // asking for the stored size changes nothing
    assert_eq!(read_sequence(&dir, 0, Some(128)).unwrap(), seq);
    // a size that does not divide uses the triangle filter, still deterministic
    let odd = read_sequence(&dir, 0, Some(48)).unwrap();
    assert_eq!(odd.frames.len(), 2 * 48 * 48 * 3);
    assert_eq!(odd, read_sequence(&dir, 0, Some(48)).unwrap());
    let err = read_sequence(&dir, 0, Some(0)).unwrap_err();
    assert_message(&err, &["image size 0"]);
}

#[test]
fn missing_frame_is_reported() {
    let (_root, dir) = written(4, &fixture(3, 8, 0));
    fs::copy(dir.join("0.png"), dir.join("5.png")).unwrap();
    fs::remove_file(dir.join("1.png")).unwrap();
    let err = read_sequence(&dir, 4, None).unwrap_err();
    assert!(
        matches!(err, DataError::MissingFrame { index: 1, .. }),
        "{err}"
    );
    assert_message(&err, &[&dir.display().to_string(), "1.png"]);
}

#[test]
fn corrupt_frame_is_reported() {
    let (_root, dir) = written(4, &fixture(3, 8, 0));
    let bad = dir.join("2.png");
    fs::write(&bad, b"\x89PNG garbage garbage garbage").unwrap();
    let err = read_sequence(&dir, 4, None).unwrap_err();
    assert!(matches!(err, DataError::CorruptFrame { .. }), "{err}");
    assert_message(&err, &[&bad.display().to_string(), "decode"]);
}

#[test]
fn frame_of_wrong_size_is_reported() {
    let seq = fixture(3, 8, 0);
    let (_root, dir) = written(4, &seq);
    let bad = dir.join("1.png");
    write_png(&bad, &seq.frames[..8 * 6 * 3], 8, 6);
    let err = read_sequence(&dir, 4, None).unwrap_err();
    assert_message(
        &err,
        &[
            &bad.display().to_string(),
            "expected a 8x8 frame (as the sequence's first), found 8x6",
        ],
    );
}

#[test]
fn wrong_column_count_is_reported() {
    let (_root, dir) = written(3, &fixture(4, 8, 0));
    let path = joint_path(&dir, 3);
    replace_line(&path, 2, "1 2 3 4 5 6");
    let err = read_sequence(&dir, 3, None).unwrap_err();
    assert_message(
        &err,
        &[&format!(
            "{} line 2: expected 7 columns, found 6",
            path.display()
        )],
    );
}

#[test]
fn non_numeric_value_is_reported() {
    let (_root, dir) = written(3, &fixture(4, 8, 0));
    let path = object_path(&dir, 3);
    replace_line(&path, 3, "0.5 abc 1.0");
    let err = read_sequence(&dir, 3, None).unwrap_err();
    assert_message(
        &err,
        &[&format!("{} line 3 column 2", path.display()), "\"abc\""],
    );
    // non-finite values are refused too
    replace_line(&path, 3, "0.5 NaN 1.0");
    let err = read_sequence(&dir, 3, None).unwrap_err();
    assert_message(&err, &["line 3 column 2", "NaN"]);
}

#[test]
fn fewer_frames_than_rows_names_the_missing_frame() {
    let (_root, dir) = written(6, &fixture(4, 8, 0));
    fs::remove_file(dir.join("1.png")).unwrap();
    fs::remove_file(dir.join("3.png")).unwrap();
    let err = read_sequence(&dir, 6, None).unwrap_err();
    assert!(matches!(
        err,
        DataError::MissingFrame {
            index: 1,
            missing: 2,
            rows: 4,
            ..
        }
    ));
    assert_message(
        &err,
        &[
            &dir.display().to_string(),
            "frame 1 is missing",
            "1.png",
            "2 of 4",
        ],
    );
}

#[test]
fn mismatched_row_counts_are_reported() {
    let (_root, dir) = written(7, &fixture(3, 8, 0));
    let path = object_path(&dir, 7);
    let content = fs::read_to_string(&path).unwrap();
    let two: Vec<&str> = content.lines().take(2).collect();
    fs::write(&path, two.join("\n")).unwrap();
    let err = read_sequence(&dir, 7, None).unwrap_err();
    assert_message(
        &err,
        &[
            &format!("{}: 2 rows, expected 3", path.display()),
            "joint_7.txt",
        ],
    );
}

#[test]
fn missing_or_empty_files_are_reported() {
    let (_root, dir) = written(8, &fixture(3, 8, 0));
    let path = joint_path(&dir, 8);
    fs::write(&path, "\n\n").unwrap();
    let err = read_sequence(&dir, 8, None).unwrap_err();
    assert_message(&err, &[&path.display().to_string(), "no rows"]);
    fs::remove_file(&path).unwrap();
    let err = read_sequence(&dir, 8, None).unwrap_err();
    assert_message(&err, &[&path.display().to_string()]);
}

#[test]
fn empty_folder_is_reported() {
    let root = tempfile::tempdir().unwrap();
    fs::write(root.path().join("LICENSE"), "MIT").unwrap();
    let err = Dataset::open(root.path()).unwrap_err();
    assert!(matches!(err, DataError::NoSequences { .. }));
    assert_message(&err, &[&root.path().display().to_string(), "no sequences"]);

    fs::create_dir(root.path().join("5")).unwrap();
    let err = Dataset::open(root.path()).unwrap_err();
    assert_message(&err, &[&root.path().join("5").display().to_string()]);

    let err = Dataset::open(root.path().join("absent")).unwrap_err();
    assert_message(&err, &["absent"]);
}

#[test]
fn dataset_writer_builds_in_a_temporary_folder() {
    let parent = tempfile::tempdir().unwrap();
    let out = parent.path().join("data");
    let mut writer = DatasetWriter::create(&out).unwrap();
    let tmp = writer.temp_dir().to_path_buf();
    assert!(tmp
        .file_name()
        .unwrap()
        .to_str()
        .unwrap()
        .starts_with("data.tmp-"));
    let seqs = [fixture(2, 8, 0), fixture(3, 8, 1), fixture(4, 8, 2)];
    writer.write(0, "grasp", &seqs[0]).unwrap();
    writer.write(0, "move", &seqs[1]).unwrap();
    writer.write(10, "grasp", &seqs[2]).unwrap();
    assert!(!out.exists(), "nothing at the final place before finish");
    assert_eq!(writer.finish().unwrap(), out);
    assert!(!tmp.exists());

    let dataset = Dataset::open(&out).unwrap();
    assert_eq!(dataset.ids(), vec![0, 10]);
    assert_eq!(dataset.actions(), vec!["grasp", "move"]);
    let read: Vec<Sequence> = dataset
        .sequences()
        .iter()
        .map(|s| dataset.read(s, None).unwrap())
        .collect();
    assert_eq!(read, seqs);
    let mut summary = Summary::new();
    for (s, seq) in dataset.sequences().iter().zip(&read) {
        summary.add(s.id, &s.action, seq);
    }
    assert_eq!(summary.sequences(), 3);
    assert_eq!(summary.actions["grasp"].min_len, 2);
    assert_eq!(summary.actions["grasp"].max_len, 4);
    let text = summary.to_string();
    assert!(
        text.contains("3 sequences, 2 ids, 7 joint values a step, frames 8x8"),
        "{text}"
    );
}

#[test]
fn unfinished_dataset_leaves_nothing() {
    let parent = tempfile::tempdir().unwrap();
    let out = parent.path().join("data");
    let mut writer = DatasetWriter::create(&out).unwrap();
    writer.write(0, "grasp", &fixture(2, 8, 0)).unwrap();
    drop(writer);
    assert_eq!(fs::read_dir(parent.path()).unwrap().count(), 0);
}

#[test]
fn non_empty_output_is_refused() {
    let parent = tempfile::tempdir().unwrap();
    let out = parent.path().join("data");
    fs::create_dir(&out).unwrap();
    // an empty folder is fine
    drop(DatasetWriter::create(&out).unwrap());
    fs::write(out.join("keep.txt"), "precious").unwrap();
    let err = DatasetWriter::create(&out).unwrap_err();
    assert!(matches!(err, DataError::OutputExists { .. }));
    assert_message(
        &err,
        &[&out.display().to_string(), "not an empty directory"],
    );
    assert_eq!(
        fs::read_to_string(out.join("keep.txt")).unwrap(),
        "precious"
    );
    // a file in the way is refused too
    let file = parent.path().join("file");
    fs::write(&file, "x").unwrap();
    assert!(matches!(
        DatasetWriter::create(&file),
        Err(DataError::OutputExists { .. })
    ));
}

#[test]
fn inconsistent_sequences_are_not_written() {
    let root = tempfile::tempdir().unwrap();
    let mut seq = fixture(3, 8, 0);
    seq.frames.pop();
    let err = write_sequence(root.path(), 1, "grasp", &seq).unwrap_err();
    assert_message(&err, &["sequence 1 (grasp)", "frame bytes"]);
    let mut seq = fixture(3, 8, 0);
    seq.object.as_mut().unwrap().pop();
    assert!(write_sequence(root.path(), 1, "grasp", &seq).is_err());
    let mut seq = fixture(3, 8, 0);
    let mut values = seq.joints.values().to_vec();
    values[seq.joints.width() + 2] = f32::NAN;
    seq.joints = Joints::new(seq.joints.width(), values).unwrap();
    assert!(write_sequence(root.path(), 1, "grasp", &seq).is_err());
    let err = write_sequence(root.path(), 1, "../up", &fixture(1, 8, 0)).unwrap_err();
    assert!(matches!(err, DataError::ActionName { .. }));
    assert_eq!(fs::read_dir(root.path()).unwrap().count(), 0);
}

/// Every file under `root` in memory, named `<name>/<path inside root>` as a browser names
/// the files of a folder the user chose; `bytes` false lists them without their bytes.
fn in_memory(root: &Path, name: &str, bytes: bool) -> MemoryFiles {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, out);
            } else {
                out.push(p);
            }
        }
    }
    let mut paths = Vec::new();
    walk(root, &mut paths);
    let rel = |p: &Path| format!("{name}/{}", p.strip_prefix(root).unwrap().display());
    let mut files = MemoryFiles::new(paths.iter().map(|p| rel(p)));
    if bytes {
        for p in &paths {
            files.put(&rel(p), fs::read(p).unwrap());
        }
    }
    files
}

#[test]
fn folder_in_memory_reads_as_on_disk() {
    let (root, _dir) = written(8, &fixture(5, 16, 3));
    write_sequence(root.path(), 8, "move", &fixture(3, 16, 1)).unwrap();
    fs::write(root.path().join("LICENSE"), "MIT").unwrap();
    let files = in_memory(root.path(), "mine", true);
    let disk = Dataset::open(root.path()).unwrap();
    let memory = Dataset::list(&files, "mine").unwrap();
    assert_eq!(memory.len(), disk.len());
    for (m, d) in memory.sequences().iter().zip(disk.sequences()) {
        assert_eq!((m.id, &m.action), (d.id, &d.action));
        assert_eq!(m.dir, Path::new("mine/8").join(&d.action));
        for size in [None, Some(8)] {
            assert_eq!(
                read_sequence_from(&files, &m.dir, m.id, None, size).unwrap(),
                disk.read(d, size).unwrap()
            );
        }
    }
    // Without the bytes, listing works and reading names the file.
    let listed = in_memory(root.path(), "mine", false);
    assert_eq!(Dataset::list(&listed, "mine").unwrap().len(), 2);
    assert!(read_sequence_from(&listed, Path::new("mine/8/grasp"), 8, None, None).is_err());
}

#[test]
fn folder_in_memory_reports_the_disk_errors() {
    // Each breakage gives the disk reader's message, with the path inside the folder.
    type Break = fn(&Path);
    let breaks: [(&str, Break); 5] = [
        ("malformed row", |dir| {
            replace_line(&joint_path(dir, 8), 2, "1 2 x")
        }),
        ("missing joint file", |dir| {
            fs::remove_file(joint_path(dir, 8)).unwrap()
        }),
        ("too few frames", |dir| {
            fs::remove_file(dir.join("2.png")).unwrap()
        }),
        ("not an image", |dir| {
            fs::write(dir.join("1.png"), "text").unwrap()
        }),
        ("non-numeric", |dir| {
            replace_line(&object_path(dir, 8), 3, "0.5 abc 1.0")
        }),
    ];
    for (what, break_it) in breaks {
        let (root, dir) = written(8, &fixture(4, 8, 0));
        break_it(&dir);
        let disk = read_sequence(&dir, 8, None).unwrap_err().to_string();
        let files = in_memory(root.path(), "mine", true);
        let memory = read_sequence_from(&files, Path::new("mine/8/grasp"), 8, None, None)
            .unwrap_err()
            .to_string();
        let prefix = format!("{}", root.path().display());
        assert_eq!(memory, disk.replace(&prefix, "mine"), "{what}");
    }
    // A folder without sequence folders.
    let empty = tempfile::tempdir().unwrap();
    fs::write(empty.path().join("LICENSE"), "MIT").unwrap();
    let files = in_memory(empty.path(), "mine", true);
    let err = Dataset::list(&files, "mine").unwrap_err();
    assert!(matches!(err, DataError::NoSequences { .. }), "{err}");
    assert_message(&err, &["mine: no sequences found"]);
}

#[test]
fn original_dataset_reads() {
    let Some(dataset) = support::dmbn2020_dataset() else {
        return;
    };
    assert_eq!(dataset.ids(), (0..40).collect::<Vec<u32>>());
    assert_eq!(dataset.actions(), vec!["grasp", "move"]);
    assert_eq!(dataset.len(), 80);
    let mut summary = Summary::new();
    for s in dataset.sequences() {
        let seq = dataset.read(s, None).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(seq.image_size, 128);
        let (lo, hi) = if s.action == "grasp" {
            (34, 86)
        } else {
            (53, 114)
        };
        assert!(
            (lo..=hi).contains(&seq.len()),
            "{}: {} steps",
            s.dir.display(),
            seq.len()
        );
        summary.add(s.id, &s.action, &seq);
    }
    assert_eq!(summary.actions["grasp"].sequences, 40);
    assert_eq!(summary.actions["move"].sequences, 40);
    // resized reading, on one sequence
    let small = dataset.read(&dataset.sequences()[0], Some(64)).unwrap();
    assert_eq!(small.image_size, 64);
    assert_eq!(small.frames.len(), small.len() * 64 * 64 * 3);
}
