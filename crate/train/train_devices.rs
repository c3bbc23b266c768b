use std::fmt;
use std::str::FromStr;

use burn::tensor::Device;

use super::{TrainDevice, TrainError};

/// The devices a run trains on (`train --devices wgpu:0,wgpu:1`, or `--device cpu`: a list of
/// one). With several, each step's batch is split evenly between them by sequence (data
/// parallelism); the first holds the model and the optimiser, and takes a share too.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TrainDevices(Vec<TrainDevice>);

impl TrainDevices {
    /// The list, first the main device; never empty.
    pub fn list(&self) -> &[TrainDevice] {
        &self.0
    }

    /// The autodiff devices, in the list's order. Fails as [`TrainDevice::device`] does.
    pub fn devices(&self) -> Result<Vec<Device>, TrainError> {
        self.0.iter().map(|d| d.device()).collect()
    }

    /// Refuses a batch (`--batch`, the whole step's) the devices cannot share equally: equal
    /// shards are what make the shards' mean loss the batch's loss.
    pub fn check_batch(&self, batch: usize) -> Result<(), TrainError> {
        let n = self.0.len();
        if batch % n == 0 {
            return Ok(());
        }
        Err(TrainError::config(
            "batch",
            format!(
                "--batch {batch} does not split evenly over the {n} devices of --devices {self}: \
                 each takes an equal share of the batch's sequences; choose a multiple of {n}"
            ),
        ))
    }
}

impl From<TrainDevice> for TrainDevices {
    fn from(device: TrainDevice) -> Self {
        TrainDevices(vec![device])
    }
}

impl FromStr for TrainDevices {
    type Err = String;

    /// Comma-separated [`TrainDevice`]s: `cpu`, `wgpu:0,wgpu:1`, `cuda:0,cuda:1`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let expected = "expected one device or a comma-separated list (cpu, wgpu:0,wgpu:1)";
        if s.trim().is_empty() {
            return Err(format!("{s:?}: no device given; {expected}"));
        }
        s.split(',')
            .enumerate()
            .map(|(i, entry)| match entry.trim() {
                "" => Err(format!("{s:?}: device {} is empty; {expected}", i + 1)),
                entry => entry.parse::<TrainDevice>(),
            })
            .collect::<Result<Vec<_>, _>>()
            .map(TrainDevices)
    }
}

impl fmt::Display for TrainDevices {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, device) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_str(",")?;
            }
            write!(f, "{device}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_are_parsed_and_bad_ones_refused_naming_the_entry() {
        let two: TrainDevices = "wgpu:0, wgpu:1".parse().unwrap();
        assert_eq!(
            two.list(),
            [TrainDevice::Wgpu(Some(0)), TrainDevice::Wgpu(Some(1))]
        );
        assert_eq!(two.to_string(), "wgpu:0,wgpu:1");
        assert_eq!(
            "cpu".parse::<TrainDevices>(),
            Ok(TrainDevices::from(TrainDevice::Cpu))
        );
        for (bad, says) in [
            ("", "no device given"),
            (" ", "no device given"),
            ("cpu,", "device 2 is empty"),
            (",cpu", "device 1 is empty"),
            ("wgpu:x", "must be a number"),
            ("cpu,gpu", "expected cpu, wgpu"),
        ] {
            let err = bad.parse::<TrainDevices>().unwrap_err();
            assert!(err.contains(says), "{bad:?}: {err}");
        }
    }

    #[test]
    fn a_batch_must_split_evenly() {
        let four: TrainDevices = "cpu,cpu,cpu,cpu".parse().unwrap();
        assert!(four.check_batch(8).is_ok());
        let err = four.check_batch(6).unwrap_err().to_string();
        assert!(
            err.contains("--batch 6") && err.contains("cpu,cpu,cpu,cpu") && err.contains("4"),
            "{err}"
        );
        assert!(TrainDevices::from(TrainDevice::Cpu).check_batch(5).is_ok());
    }
}
