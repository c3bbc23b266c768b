use std::ops::Index;

/// The arm joints (radians) among `d` joint values: all but the last, the gripper by the
/// layout's convention (a single value is an arm joint, and there is no gripper).
pub fn arm_joints(d: usize) -> usize {
    if d > 1 {
        d - 1
    } else {
        d
    }
}

/// The joint values of one sequence: `len()` steps of `width()` values each, stored row by row.
/// The width D is the robot's, read from its data (the original arm's 7: six angles, then
/// the gripper), never a constant of the code.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Joints {
    width: usize,
    values: Vec<f32>,
}

impl Joints {
    /// `values` as rows of `width`; `None` unless `width > 0` and it divides `values`' length.
    pub fn new(width: usize, values: Vec<f32>) -> Option<Self> {
        (width > 0 && values.len() % width == 0).then_some(Joints { width, values })
    }

    /// Rows of a fixed-size array type (tests, the simulator's arm).
    pub fn from_rows<const D: usize>(rows: &[[f32; D]]) -> Self {
        Joints {
            width: D,
            values: rows.iter().flatten().copied().collect(),
        }
    }

    /// Rows given as slices, each `width` long (checked).
    pub fn from_slices<'a>(width: usize, rows: impl IntoIterator<Item = &'a [f32]>) -> Self {
        let mut values = Vec::new();
        for row in rows {
            assert_eq!(row.len(), width, "a joint row of another width");
            values.extend_from_slice(row);
        }
        Joints { width, values }
    }

    /// Values per step (D).
    pub fn width(&self) -> usize {
        self.width
    }

    /// Number of steps.
    pub fn len(&self) -> usize {
        self.values.len().checked_div(self.width).unwrap_or(0)
    }

    /// True without a step.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// The values of step `k`.
    pub fn row(&self, k: usize) -> &[f32] {
        &self.values[k * self.width..(k + 1) * self.width]
    }

    /// The values of step `k`, to change.
    pub fn row_mut(&mut self, k: usize) -> &mut [f32] {
        &mut self.values[k * self.width..(k + 1) * self.width]
    }

    /// Every step's values, in order.
    pub fn rows(&self) -> std::slice::ChunksExact<'_, f32> {
        self.values.chunks_exact(self.width.max(1))
    }

    /// All values, step after step.
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// The first `steps` steps (all of them when there are fewer).
    pub fn truncated(&self, steps: usize) -> Joints {
        let n = steps.min(self.len()) * self.width;
        Joints {
            width: self.width,
            values: self.values[..n].to_vec(),
        }
    }

    /// Append one step (`width` values).
    pub fn push(&mut self, row: &[f32]) {
        assert_eq!(row.len(), self.width, "a joint row of another width");
        self.values.extend_from_slice(row);
    }

    /// An empty table of `width` values a step.
    pub fn with_width(width: usize) -> Self {
        Joints {
            width,
            values: Vec::new(),
        }
    }
}

impl Index<usize> for Joints {
    type Output = [f32];

    fn index(&self, k: usize) -> &[f32] {
        self.row(k)
    }
}

/// Rows of the simulator's (or any fixed) width: `[f32; N]` rows collect into a table of N.
impl<const N: usize> FromIterator<[f32; N]> for Joints {
    fn from_iter<I: IntoIterator<Item = [f32; N]>>(rows: I) -> Self {
        Joints {
            width: N,
            values: rows.into_iter().flatten().collect(),
        }
    }
}

impl<'a> IntoIterator for &'a Joints {
    type Item = &'a [f32];
    type IntoIter = std::slice::ChunksExact<'a, f32>;

    fn into_iter(self) -> Self::IntoIter {
        self.rows()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_of_any_width() {
        let j = Joints::new(3, (0..6).map(|v| v as f32).collect()).unwrap();
        assert_eq!((j.width(), j.len()), (3, 2));
        assert_eq!(&j[1], &[3.0, 4.0, 5.0]);
        assert_eq!(j.rows().count(), 2);
        assert_eq!(j.truncated(1).values(), &[0.0, 1.0, 2.0]);
        assert!(Joints::new(4, vec![0.0; 6]).is_none());
        assert!(Joints::new(0, vec![]).is_none());
        assert_eq!(Joints::from_rows(&[[1.0f32, 2.0]]).width(), 2);
    }
}
