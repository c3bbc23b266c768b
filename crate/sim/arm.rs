use std::fmt;
use std::str::FromStr;

use super::SimError;

/// The arms the simulator models, each with the same parallel gripper: the joint values a
/// step are the arm's angles, then the gripper, so a data set's width names its arm.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub enum Arm {
    /// A UR5-like arm: 6 revolute joints (7 values a step). The original data's arm.
    #[default]
    Ur5,
    /// A Franka-Panda-like arm: 7 revolute joints, one of them redundant (8 values a step).
    Panda,
}

impl Arm {
    /// Every arm, the default first.
    pub const ALL: [Arm; 2] = [Arm::Ur5, Arm::Panda];

    /// The name the command line and the page use.
    pub fn name(self) -> &'static str {
        match self {
            Arm::Ur5 => "ur5",
            Arm::Panda => "panda",
        }
    }

    /// Revolute joints before the gripper.
    pub fn joints(self) -> usize {
        match self {
            Arm::Ur5 => 6,
            Arm::Panda => 7,
        }
    }

    /// Joint values a step: the angles, then the gripper.
    pub fn width(self) -> usize {
        self.joints() + 1
    }

    /// The arm whose rows are `width` values wide; fails naming the widths that exist.
    pub fn of_width(width: usize) -> Result<Arm, SimError> {
        Arm::ALL
            .into_iter()
            .find(|a| a.width() == width)
            .ok_or(SimError::ArmWidth(width))
    }

    /// "7 (ur5) or 8 (panda)": the widths of joint rows the simulator performs.
    pub fn widths_text() -> String {
        let widths: Vec<String> = Arm::ALL
            .iter()
            .map(|a| format!("{} ({a})", a.width()))
            .collect();
        widths.join(" or ")
    }

    /// "\"ur5\" or \"panda\"": the arm names.
    pub fn names_text() -> String {
        let names: Vec<String> = Arm::ALL.iter().map(|a| format!("{:?}", a.name())).collect();
        names.join(" or ")
    }
}

impl fmt::Display for Arm {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Arm {
    type Err = SimError;
    fn from_str(s: &str) -> Result<Self, SimError> {
        Arm::ALL
            .into_iter()
            .find(|a| a.name() == s)
            .ok_or_else(|| SimError::UnknownArm(s.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arms_parse_by_name_and_are_named_by_width() {
        assert_eq!("ur5".parse::<Arm>().unwrap(), Arm::Ur5);
        assert_eq!("panda".parse::<Arm>().unwrap(), Arm::Panda);
        let err = "kuka".parse::<Arm>().unwrap_err().to_string();
        assert!(
            err.contains("\"kuka\"") && err.contains("\"ur5\" or \"panda\""),
            "{err}"
        );
        assert_eq!(Arm::of_width(7).unwrap(), Arm::Ur5);
        assert_eq!(Arm::of_width(8).unwrap(), Arm::Panda);
        let err = Arm::of_width(9).unwrap_err().to_string();
        assert!(
            err.contains("9 joint values") && err.contains("7 (ur5) or 8 (panda)"),
            "{err}"
        );
        assert_eq!(Arm::default(), Arm::Ur5);
    }
}
