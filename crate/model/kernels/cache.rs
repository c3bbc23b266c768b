//! The prepared kernels an image network keeps between calls.
use burn::nn::conv::Conv2d;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use super::plan::Kernels;

/// Prepared convolutions kept by an image network, one slot per layer: preparing the kernels
/// is costly next to a decode, so they are prepared once and reused while the weights
/// they came from stay the same: compared exactly on each use (training or loading other
/// weights prepares them anew) unless the owner has promised, with
/// [`KernelCache::freeze`], that they never change. A copy of the network (a clone, as burn
/// makes for `valid()` or before an update) starts with an empty cache of its own.
#[derive(Debug, Default)]
pub(crate) struct KernelCache {
    slots: Mutex<Vec<Option<Arc<Kernels>>>>,
    frozen: AtomicBool,
}

impl Clone for KernelCache {
    fn clone(&self) -> Self {
        KernelCache::default()
    }
}

impl KernelCache {
    /// Promises that the network's weights will not change any more (its owner only ever
    /// reads it, as a [`Predictor`](crate::predict::Predictor) does), so prepared kernels are
    /// reused without comparing the weights (a cost comparable to a one-target prediction's
    /// own).
    ///
    /// Kernels prepared before are dropped: they may come from earlier weights.
    pub(crate) fn freeze(&self) {
        let mut slots = self.slots.lock().unwrap_or_else(|e| e.into_inner());
        slots.clear();
        self.frozen.store(true, Ordering::Relaxed);
    }

    /// Whether [`KernelCache::freeze`] was called.
    pub(crate) fn is_frozen(&self) -> bool {
        self.frozen.load(Ordering::Relaxed)
    }

    /// The kernels of `convs` in `slot`, prepared now if the slot is empty or holds others.
    pub(crate) fn get(
        &self,
        slot: usize,
        convs: &[&Conv2d],
        c_in: usize,
        upsampled: bool,
    ) -> Arc<Kernels> {
        let mut slots = self.slots.lock().unwrap_or_else(|e| e.into_inner());
        if slots.len() <= slot {
            slots.resize(slot + 1, None);
        }
        if let Some(k) = &slots[slot] {
            if k.upsampled == upsampled && self.frozen.load(Ordering::Relaxed) {
                return k.clone();
            }
        }
        let (weights, bias) = Kernels::read(convs, c_in);
        if let Some(k) = &slots[slot] {
            if k.upsampled == upsampled && k.weights == weights && k.bias == bias {
                return k.clone();
            }
        }
        let kernels = Arc::new(Kernels::prepare(weights, bias, c_in, upsampled));
        slots[slot] = Some(kernels.clone());
        kernels
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::init::conv3x3;
    use crate::model::kernels::{Activation, FeatureMap};
    use crate::model::testing::max_abs_diff;
    use burn::tensor::{Device, Distribution, Tensor};

    #[test]
    fn the_cache_reuses_kernels_only_while_the_weights_are_the_same() {
        let device = Device::flex();
        device.seed(5);
        let (a, b) = (conv3x3([3, 4], &device), conv3x3([3, 4], &device));
        let x = Tensor::<4>::random([2, 3, 4, 4], Distribution::Default, &device);
        let map = FeatureMap::from_channels_first(x.clone());
        let cache = KernelCache::default();
        let first = cache.get(0, &[&a], 3, false);
        assert!(Arc::ptr_eq(&first, &cache.get(0, &[&a], 3, false)));
        // Other weights in the same slot (as after a training step) are prepared anew.
        let other = cache.get(0, &[&b], 3, false);
        assert!(!Arc::ptr_eq(&first, &other));
        let got = map.conv3x3(&other, Activation::Identity);
        let got = got.into_channels_first(&[4], &device).remove(0);
        assert!(max_abs_diff(got, b.forward(x)) < 1e-5);
        let upsampled = cache.get(0, &[&b], 3, true);
        assert!(!Arc::ptr_eq(&other, &upsampled));
        // Frozen, the slot's kernels stand whatever weights are passed (the owner promised no
        // change); a copy of the cache starts empty.
        cache.freeze();
        let frozen = cache.get(0, &[&b], 3, true);
        assert!(!Arc::ptr_eq(&upsampled, &frozen), "freezing starts afresh");
        assert!(Arc::ptr_eq(&frozen, &cache.get(0, &[&a], 3, true)));
        let copy = cache.clone();
        assert!(!Arc::ptr_eq(&frozen, &copy.get(0, &[&b], 3, true)));
        // No frames at all (a prediction of no target times) is an empty map, not a panic.
        let empty = FeatureMap {
            data: Vec::new(),
            shape: [0, 4, 4, 3],
        };
        assert_eq!(empty.conv3x3(&other, Activation::Relu).shape, [0, 4, 4, 4]);
    }
}
