//! Reading one sequence folder of the DMBN layout, validating every file on the way.
use std::collections::HashMap;
use std::io;
use std::path::{Path, PathBuf};

use image::imageops::FilterType;
use image::RgbImage;

use super::layout::{endpoint_path, joint_path, object_path, MAX_IMAGE_SIZE};
use super::{DataError, Disk, Files, Joints, Sequence, ENDPOINT};

/// Frame file extensions, in order of preference when one step has several.
const FRAME_EXTENSIONS: [&str; 3] = ["png", "jpeg", "jpg"];

/// Read the sequence in `dir` (`joint_<id>.txt`, optionally `object_<id>.txt` and
/// `endpoint_<id>.txt`, and frames `0.png`/`0.jpeg` …). Frames beyond the joint rows are
/// ignored (the original folders often hold a few). With `image_size`, frames are resized to
/// that many pixels per side (see [`read_frames`]); without, square frames are kept as they
/// are and others stretched to the square of their longer side.
pub fn read_sequence(dir: &Path, id: u32, image_size: Option<u32>) -> Result<Sequence, DataError> {
    read_sequence_from(&Disk, dir, id, None, image_size)
}

/// [`read_sequence`] on any [`Files`] (the page reads a folder held in memory with the same
/// rules and messages as the tools read the disk), the frames of `camera` (its sub-folder
/// `<dir>/<camera>/`; `None`: the default camera's frames in `dir` itself).
pub fn read_sequence_from(
    files: &impl Files,
    dir: &Path,
    id: u32,
    camera: Option<&str>,
    image_size: Option<u32>,
) -> Result<Sequence, DataError> {
    if let Some(size) = image_size {
        if size == 0 || size > MAX_IMAGE_SIZE {
            return Err(DataError::ImageSize { size });
        }
    }
    let joint_file = joint_path(dir, id);
    let joints = read_joints(files, dir, id)?;
    let rows = joints.len();
    let present = files.files(dir)?;
    let object = optional_table::<3>(files, &present, &object_path(dir, id))?;
    let endpoint = optional_table::<ENDPOINT>(files, &present, &endpoint_path(dir, id))?;
    for (path, found) in [
        (object_path(dir, id), object.as_ref().map(Vec::len)),
        (endpoint_path(dir, id), endpoint.as_ref().map(Vec::len)),
    ] {
        if let Some(found) = found.filter(|&n| n != rows) {
            return Err(DataError::RowMismatch {
                path,
                found,
                expected: rows,
                reference: joint_file,
            });
        }
    }

    let frames_dir = camera_dir(dir, camera);
    let paths = frame_paths(files, &frames_dir, rows)?;
    let mut frames = Vec::new();
    let mut size = None;
    for path in &paths {
        let (stored, frame) = load_frame(files, path, size, image_size)?;
        size = Some(stored);
        frames.extend_from_slice(&frame);
    }
    Ok(Sequence {
        image_size: image_size
            .or(size.map(|s: (u32, u32)| s.0.max(s.1)))
            .unwrap_or(0),
        joints,
        endpoint,
        object,
        frames,
    })
}

/// The folder holding `camera`'s frames: `<dir>/<camera>/`, or `dir` for the default camera.
pub fn camera_dir(dir: &Path, camera: Option<&str>) -> PathBuf {
    match camera {
        Some(name) => dir.join(name),
        None => dir.to_path_buf(),
    }
}

/// The joints (`joint_<id>.txt`) of the sequence in `dir` alone: what training holds in memory
/// of every sequence, reading frames only when a batch needs them ([`read_frames`]). The
/// number of values a step is the file's first row's; every row must have as many.
pub fn read_joints(files: &impl Files, dir: &Path, id: u32) -> Result<Joints, DataError> {
    let path = joint_path(dir, id);
    let (width, values) = read_values(files, &path, None)?;
    Ok(Joints::new(width, values).expect("rows of the width read"))
}

/// Frames `steps` of the `rows`-step sequence whose frames are in `dir` (a camera's folder,
/// [`camera_dir`]), each as [`read_sequence`] reads it: resized to `image_size` pixels a side,
/// an exact area average when it divides a square stored size (128 → 64), otherwise a
/// triangle filter (a frame of another aspect is stretched to the square); both
/// deterministic. A training batch decodes only the steps it holds; that all frames have one
/// size is [`read_sequence`]'s check, which sees them all.
pub fn read_frames(
    files: &impl Files,
    dir: &Path,
    rows: usize,
    steps: &[usize],
    image_size: u32,
) -> Result<Vec<Vec<u8>>, DataError> {
    if image_size == 0 || image_size > MAX_IMAGE_SIZE {
        return Err(DataError::ImageSize { size: image_size });
    }
    let paths = frame_paths(files, dir, rows)?;
    steps
        .iter()
        .map(|&k| {
            let path = paths.get(k).ok_or_else(|| DataError::MissingFrame {
                dir: dir.to_path_buf(),
                index: k,
                missing: 1,
                rows,
            })?;
            Ok(load_frame(files, path, None, Some(image_size))?.1)
        })
        .collect()
}

/// The frame at `path` as RGB bytes, resized to `image_size` when given (else a square
/// stored frame as it is), and its stored size: it must be `expected` (any size when `None`).
fn load_frame(
    files: &impl Files,
    path: &Path,
    expected: Option<(u32, u32)>,
    image_size: Option<u32>,
) -> Result<((u32, u32), Vec<u8>), DataError> {
    let img = read_frame(files, path)?;
    let stored = img.dimensions();
    let expected = expected.unwrap_or(stored);
    if stored != expected {
        return Err(DataError::FrameSize {
            path: path.to_path_buf(),
            expected,
            found: stored,
        });
    }
    // Unresized, a frame of another aspect is stretched to the square of its longer side.
    let side = image_size.unwrap_or(stored.0.max(stored.1));
    let img = if (side, side) == stored {
        img
    } else {
        resize(&img, side)
    };
    Ok((stored, img.into_raw()))
}

/// [`read_table`] of the file at `path` when it is one of `present` (its folder's file names),
/// `None` without it.
fn optional_table<const N: usize>(
    files: &impl Files,
    present: &[String],
    path: &Path,
) -> Result<Option<Vec<[f32; N]>>, DataError> {
    let name = path.file_name().and_then(|n| n.to_str());
    if !name.is_some_and(|n| present.iter().any(|p| p == n)) {
        return Ok(None);
    }
    read_table(files, path).map(Some)
}

/// Parse a whitespace-separated table of `N` finite numbers per row.
fn read_table<const N: usize>(files: &impl Files, path: &Path) -> Result<Vec<[f32; N]>, DataError> {
    let (_, values) = read_values(files, path, Some(N))?;
    Ok(values
        .chunks_exact(N)
        .map(|row| row.try_into().expect("N values"))
        .collect())
}

/// Parse a whitespace-separated table of finite numbers, `width` per row (the first row's
/// count when `None`), returned with its width. Trailing blank lines are allowed; any other
/// line must have exactly `width` values.
fn read_values(
    files: &impl Files,
    path: &Path,
    width: Option<usize>,
) -> Result<(usize, Vec<f32>), DataError> {
    let bytes = files.read(path)?;
    let text = std::str::from_utf8(&bytes).map_err(|e| DataError::Io {
        path: path.to_path_buf(),
        source: io::Error::new(io::ErrorKind::InvalidData, e),
    })?;
    let lines: Vec<&str> = text.lines().collect();
    let used = lines
        .iter()
        .rposition(|l| !l.trim().is_empty())
        .map_or(0, |i| i + 1);
    let mut values = Vec::new();
    let mut width = width;
    for (i, line) in lines[..used].iter().enumerate() {
        let fields: Vec<&str> = line.split_whitespace().collect();
        let expected = *width.get_or_insert(fields.len());
        if fields.len() != expected || expected == 0 {
            return Err(DataError::Columns {
                path: path.to_path_buf(),
                line: i + 1,
                expected: expected.max(1),
                found: fields.len(),
            });
        }
        for (c, field) in fields.iter().enumerate() {
            let value = match field.parse::<f32>() {
                Ok(v) if v.is_finite() => v,
                _ => {
                    return Err(DataError::NonNumeric {
                        path: path.to_path_buf(),
                        line: i + 1,
                        column: c + 1,
                        text: (*field).to_string(),
                    })
                }
            };
            values.push(value);
        }
    }
    match width {
        Some(width) if !values.is_empty() => Ok((width, values)),
        _ => Err(DataError::NoRows {
            path: path.to_path_buf(),
        }),
    }
}

/// Paths of frames `0..rows` in `dir`, checking there are enough and none is missing.
fn frame_paths(files: &impl Files, dir: &Path, rows: usize) -> Result<Vec<PathBuf>, DataError> {
    // step index -> (preference, path)
    let mut found: HashMap<usize, (usize, PathBuf)> = HashMap::new();
    for name in files.files(dir)? {
        let Some((stem, ext)) = name.rsplit_once('.') else {
            continue;
        };
        let Some(pref) = FRAME_EXTENSIONS
            .iter()
            .position(|e| e.eq_ignore_ascii_case(ext))
        else {
            continue;
        };
        if stem.is_empty() || !stem.bytes().all(|b| b.is_ascii_digit()) {
            continue;
        }
        let Ok(index) = stem.parse::<usize>() else {
            continue;
        };
        let path = dir.join(&name);
        found
            .entry(index)
            .and_modify(|cur| {
                if pref < cur.0 {
                    *cur = (pref, path.clone());
                }
            })
            .or_insert((pref, path));
    }
    let missing: Vec<usize> = (0..rows).filter(|i| !found.contains_key(i)).collect();
    if let Some(&index) = missing.first() {
        return Err(DataError::MissingFrame {
            dir: dir.to_path_buf(),
            index,
            missing: missing.len(),
            rows,
        });
    }
    Ok((0..rows)
        .filter_map(|index| found.remove(&index).map(|(_, p)| p))
        .collect())
}

/// Decode one frame (format from its content) as RGB8.
fn read_frame(files: &impl Files, path: &Path) -> Result<RgbImage, DataError> {
    let bytes = files.read(path)?;
    let img = image::load_from_memory(&bytes).map_err(|source| DataError::CorruptFrame {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(img.to_rgb8())
}

/// Resize a frame to `target` pixels per side: an exact, rounded area average when the frame
/// is square and `target` divides its size (integer arithmetic, identical on every
/// platform), otherwise image's triangle filter (stretching another aspect to the square).
fn resize(img: &RgbImage, target: u32) -> RgbImage {
    let size = img.width();
    if img.height() == size && target < size && size % target == 0 {
        let f = size / target;
        let n = f * f;
        RgbImage::from_fn(target, target, |x, y| {
            let mut sum = [0u32; 3];
            for dy in 0..f {
                for dx in 0..f {
                    let p = img.get_pixel(x * f + dx, y * f + dy);
                    for (s, v) in sum.iter_mut().zip(p.0) {
                        *s += u32::from(v);
                    }
                }
            }
            image::Rgb(sum.map(|s| ((s + n / 2) / n) as u8))
        })
    } else {
        image::imageops::resize(img, target, target, FilterType::Triangle)
    }
}
