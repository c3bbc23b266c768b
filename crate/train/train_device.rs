use std::fmt;
use std::str::FromStr;

use burn::tensor::Device;

use super::TrainError;

/// Where a run trains (`train --device`): the CPU (burn's `flex`, always built), a GPU through
/// burn's `wgpu` backend (Vulkan, Metal, DX12; the cargo feature `wgpu`) or through `cuda`
/// (the cargo feature `cuda`, whose build downloads LLVM). A GPU is never needed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TrainDevice {
    /// The CPU, with the project's own kernels.
    #[default]
    Cpu,
    /// A wgpu adapter: `None` is wgpu's choice (the high-power GPU, or
    /// `CUBECL_WGPU_DEFAULT_DEVICE`; a software Vulkan driver where nothing else is), `Some(n)`
    /// the n-th discrete GPU.
    Wgpu(Option<usize>),
    /// The n-th CUDA GPU.
    Cuda(usize),
}

impl TrainDevice {
    /// The autodiff device a run trains on. Fails, saying how to build it, for a backend this
    /// build does not have.
    pub fn device(self) -> Result<Device, TrainError> {
        let device = match self {
            TrainDevice::Cpu => Device::flex(),
            TrainDevice::Wgpu(index) => wgpu(index)?,
            TrainDevice::Cuda(index) => cuda(index)?,
        };
        Ok(device.autodiff())
    }
}

#[cfg(feature = "wgpu")]
fn wgpu(index: Option<usize>) -> Result<Device, TrainError> {
    use burn::tensor::DeviceKind;
    Ok(Device::wgpu(index.map_or(
        DeviceKind::DefaultDevice,
        DeviceKind::DiscreteGpu,
    )))
}

#[cfg(not(feature = "wgpu"))]
fn wgpu(_: Option<usize>) -> Result<Device, TrainError> {
    Err(not_built("wgpu"))
}

#[cfg(feature = "cuda")]
fn cuda(index: usize) -> Result<Device, TrainError> {
    Ok(Device::cuda(index))
}

#[cfg(not(feature = "cuda"))]
fn cuda(_: usize) -> Result<Device, TrainError> {
    Err(not_built("cuda"))
}

#[cfg(any(not(feature = "wgpu"), not(feature = "cuda")))]
fn not_built(backend: &str) -> TrainError {
    TrainError::config(
        "device",
        format!(
            "{backend}: this build has no {backend} backend (build with `cargo build --release \
             --features {backend}`; see README, Training on a GPU)"
        ),
    )
}

impl FromStr for TrainDevice {
    type Err = String;

    /// `cpu`, `wgpu`, `wgpu:N` or `cuda[:N]`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let (name, index) = match s.split_once(':') {
            Some((name, index)) => {
                let index = index.parse::<usize>().map_err(|_| {
                    format!("{s:?}: the device index must be a number (wgpu:0, cuda:1)")
                })?;
                (name, Some(index))
            }
            None => (s, None),
        };
        match (name, index) {
            ("cpu", None) => Ok(TrainDevice::Cpu),
            ("wgpu", index) => Ok(TrainDevice::Wgpu(index)),
            ("cuda", index) => Ok(TrainDevice::Cuda(index.unwrap_or(0))),
            _ => Err(format!(
                "{s:?}: expected cpu, wgpu, wgpu:N (the N-th discrete GPU) or cuda[:N]"
            )),
        }
    }
}

impl fmt::Display for TrainDevice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TrainDevice::Cpu => f.write_str("cpu"),
            TrainDevice::Wgpu(None) => f.write_str("wgpu"),
            TrainDevice::Wgpu(Some(n)) => write!(f, "wgpu:{n}"),
            TrainDevice::Cuda(n) => write!(f, "cuda:{n}"),
        }
    }
}
