use serde::Serialize;

use super::PushMiss;

/// Where a pushed object ended against the demonstration's spot, along and across the
/// demonstration's push, cm: a missed push went short, long, or aside.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PushError {
    /// Along the push: negative short of the demonstration's spot, positive beyond it.
    pub along: f32,
    /// Across the push: positive to its left (seen from above), negative to its right.
    pub across: f32,
}

impl PushError {
    /// `performed`'s final object position against the demonstration's `goal`, resolved along
    /// the demonstration's push from `start`; `None` when its object moved less than 1 mm.
    pub(super) fn of(start: &[f32; 3], goal: &[f32; 3], performed: &[f32; 3]) -> Option<Self> {
        let (dx, dy) = (goal[0] - start[0], goal[1] - start[1]);
        let travel = (dx * dx + dy * dy).sqrt();
        if travel < 1e-3 {
            return None;
        }
        let (ux, uy) = (dx / travel, dy / travel);
        let (ex, ey) = (performed[0] - goal[0], performed[1] - goal[1]);
        Some(PushError {
            along: (ex * ux + ey * uy) * 100.0,
            across: (ey * ux - ex * uy) * 100.0,
        })
    }

    /// Which way the push missed.
    pub fn miss(&self) -> PushMiss {
        if self.across.abs() > self.along.abs() {
            PushMiss::Aside
        } else if self.along < 0.0 {
            PushMiss::Short
        } else {
            PushMiss::Long
        }
    }
}

impl std::fmt::Display for PushError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let along = if self.along < 0.0 { "short" } else { "beyond" };
        let side = if self.across < 0.0 { "right" } else { "left" };
        write!(
            f,
            "{:.1} cm {along}, {:.1} cm to the {side}",
            self.along.abs(),
            self.across.abs()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_resolve_along_and_across_the_demonstrations_push() {
        // The demonstration pushes 20 cm along +x; left of it is +y.
        let (start, goal) = ([0.0, 0.5, 0.05], [0.2, 0.5, 0.05]);
        let at = |x: f32, y: f32| PushError::of(&start, &goal, &[x, y, 0.05]).unwrap();
        let short = at(0.16, 0.51);
        assert!((short.along + 4.0).abs() < 1e-4 && (short.across - 1.0).abs() < 1e-4);
        assert_eq!(short.miss(), PushMiss::Short);
        assert_eq!(short.to_string(), "4.0 cm short, 1.0 cm to the left");
        let long = at(0.25, 0.5);
        assert_eq!(long.miss(), PushMiss::Long);
        let aside = at(0.19, 0.44);
        assert!((aside.across + 6.0).abs() < 1e-4, "{aside:?}");
        assert_eq!(aside.miss(), PushMiss::Aside);
        assert_eq!(aside.to_string(), "1.0 cm short, 6.0 cm to the right");
        // Along -y the left is +x: the frame turns with the push.
        let turned = PushError::of(&start, &[0.0, 0.3, 0.05], &[0.05, 0.3, 0.05]).unwrap();
        assert!((turned.across - 5.0).abs() < 1e-4 && turned.along.abs() < 1e-4);
        // An object that never moved in the demonstration has no push direction.
        assert_eq!(PushError::of(&start, &start, &goal), None);
    }
}
