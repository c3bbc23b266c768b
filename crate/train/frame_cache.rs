use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

/// Decoded training frames by (sequence, step), at most `capacity` bytes of them: the least
/// recently used leave first. Training reads frames from disk instead of holding the dataset;
/// this keeps the ones drawn again (all of them, for a dataset that fits) from being decoded
/// twice, within a bound that does not grow with the dataset.
#[derive(Debug)]
pub(crate) struct FrameCache {
    capacity: usize,
    bytes: usize,
    frames: HashMap<(usize, usize), Held>,
    /// The frames by last use, oldest first.
    by_use: BTreeMap<u64, (usize, usize)>,
    clock: u64,
}

/// A frame in the cache and when it was last used.
#[derive(Debug)]
struct Held {
    frame: Arc<[u8]>,
    used: u64,
}

impl FrameCache {
    /// An empty cache of at most `capacity` bytes of frames (0 keeps none).
    pub fn new(capacity: usize) -> FrameCache {
        FrameCache {
            capacity,
            bytes: 0,
            frames: HashMap::new(),
            by_use: BTreeMap::new(),
            clock: 0,
        }
    }

    /// Step `step` of sequence `sequence`, if held; it becomes the most recently used.
    pub fn get(&mut self, sequence: usize, step: usize) -> Option<Arc<[u8]>> {
        let held = self.frames.get_mut(&(sequence, step))?;
        self.by_use.remove(&held.used);
        self.clock += 1;
        held.used = self.clock;
        self.by_use.insert(self.clock, (sequence, step));
        Some(held.frame.clone())
    }

    /// Keep `frame` as step `step` of sequence `sequence`, dropping the least recently used
    /// frames until it fits (a frame larger than the whole cache is not kept).
    pub fn insert(&mut self, sequence: usize, step: usize, frame: Arc<[u8]>) {
        if let Some(old) = self.frames.remove(&(sequence, step)) {
            self.by_use.remove(&old.used);
            self.bytes -= old.frame.len();
        }
        if frame.len() > self.capacity {
            return;
        }
        while self.bytes + frame.len() > self.capacity {
            let Some((_, key)) = self.by_use.pop_first() else {
                break;
            };
            if let Some(old) = self.frames.remove(&key) {
                self.bytes -= old.frame.len();
            }
        }
        self.clock += 1;
        self.bytes += frame.len();
        let used = self.clock;
        self.frames.insert((sequence, step), Held { frame, used });
        self.by_use.insert(self.clock, (sequence, step));
    }

    /// Bytes of frames held: never above the capacity.
    #[cfg(test)]
    pub fn bytes(&self) -> usize {
        self.bytes
    }

    /// Frames held.
    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.frames.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(tag: u8, bytes: usize) -> Arc<[u8]> {
        vec![tag; bytes].into()
    }

    #[test]
    fn it_stays_within_its_bound_and_drops_the_least_recently_used() {
        let mut cache = FrameCache::new(100);
        for k in 0..5 {
            cache.insert(0, k, frame(k as u8, 30));
            assert!(cache.bytes() <= 100, "{} bytes after {k}", cache.bytes());
        }
        // Room for three: steps 2, 3 and 4 are left.
        assert_eq!((cache.len(), cache.bytes()), (3, 90));
        assert!(cache.get(0, 1).is_none());
        // Step 2 used again: step 3 is now the oldest and leaves next.
        assert_eq!(&*cache.get(0, 2).unwrap(), &[2u8; 30][..]);
        cache.insert(1, 0, frame(9, 30));
        assert!(cache.get(0, 3).is_none());
        assert!(cache.get(0, 2).is_some() && cache.get(0, 4).is_some());
        assert_eq!(&*cache.get(1, 0).unwrap(), &[9u8; 30][..]);
        // Replacing a frame counts its bytes once; one larger than the cache is not kept.
        cache.insert(1, 0, frame(8, 30));
        assert_eq!((cache.len(), cache.bytes()), (3, 90));
        cache.insert(2, 0, frame(7, 101));
        assert!(cache.get(2, 0).is_none());
        assert!(cache.bytes() <= 100);
        let mut none = FrameCache::new(0);
        none.insert(0, 0, frame(1, 1));
        assert_eq!((none.len(), none.bytes()), (0, 0));
    }
}
