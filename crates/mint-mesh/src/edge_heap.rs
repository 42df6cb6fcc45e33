//! The priority queue of the quadric collapse ([`crate::qem`]): one entry
//! per edge, keyed by (cost, u, v), whose key is changed in place when a
//! collapse prices the edge again, and which an edge leaves when it is
//! refused or goes. A lazy heap (push a new entry, skip the stale ones when
//! they come up) popped about nine entries per collapse on real meshes and
//! grew to twice the edges; this one pops one per decision and holds at
//! most the live edges.
//!
//! A 4-ary heap: half the levels of a binary one, and a node's children side
//! by side in memory. Keys are totally ordered and unique per live edge, so
//! the order of the pops is the keys' order whatever the sequence of
//! updates: the collapse's result does not depend on the heap.

/// An edge's key: its collapse cost (f64 bits: non-negative, so they order
/// as the values) and its ends `u < v`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct Key {
    pub cost_bits: u64,
    pub u: u32,
    pub v: u32,
}

const OUT: u32 = u32::MAX;

/// A 4-ary min-heap of edge ids by [`Key`], with each id's place in it.
pub(crate) struct EdgeHeap {
    v: Vec<(Key, u32)>,
    /// Per edge id, its index in `v`, or [`OUT`].
    at: Vec<u32>,
}

impl EdgeHeap {
    /// A heap of `entries` (ids below `ids`, each at most once; Floyd's
    /// bottom-up construction).
    pub fn from(entries: Vec<(Key, u32)>, ids: usize) -> EdgeHeap {
        let mut h = EdgeHeap { v: entries, at: vec![OUT; ids] };
        for (i, e) in h.v.iter().enumerate() {
            h.at[e.1 as usize] = i as u32;
        }
        for i in (0..h.v.len().div_ceil(4)).rev() {
            h.sift_down(i);
        }
        h
    }

    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.v.len()
    }

    /// Room for ids below `ids`.
    pub fn grow(&mut self, ids: usize) {
        if self.at.len() < ids {
            self.at.resize(ids, OUT);
        }
    }

    pub fn contains(&self, id: u32) -> bool {
        self.at[id as usize] != OUT
    }

    /// Puts `id` in with `key`, or changes its key.
    pub fn set(&mut self, id: u32, key: Key) {
        let i = self.at[id as usize];
        if i == OUT {
            self.v.push((key, id));
            self.sift_up(self.v.len() - 1);
        } else {
            let i = i as usize;
            let old = std::mem::replace(&mut self.v[i].0, key);
            self.restore(i, old);
        }
    }

    /// Takes `id` out (nothing when it is not in).
    pub fn remove(&mut self, id: u32) {
        let i = self.at[id as usize];
        if i == OUT {
            return;
        }
        self.at[id as usize] = OUT;
        let last = self.v.pop().expect("an id in the heap");
        let i = i as usize;
        if i < self.v.len() {
            let old = std::mem::replace(&mut self.v[i], last).0;
            self.at[last.1 as usize] = i as u32;
            self.restore(i, old);
        }
    }

    /// The least key and its id, left in.
    pub fn peek(&self) -> Option<(Key, u32)> {
        self.v.first().copied()
    }

    /// Moves the entry at `i`, whose key was `old`, to where its key goes.
    fn restore(&mut self, i: usize, old: Key) {
        if self.v[i].0 < old {
            self.sift_up(i);
        } else {
            self.sift_down(i);
        }
    }

    /// Entry `e` at index `i`.
    fn put(&mut self, i: usize, e: (Key, u32)) {
        self.v[i] = e;
        self.at[e.1 as usize] = i as u32;
    }

    fn sift_up(&mut self, mut i: usize) {
        let e = self.v[i];
        while i > 0 {
            let parent = (i - 1) / 4;
            if self.v[parent].0 <= e.0 {
                break;
            }
            self.put(i, self.v[parent]);
            i = parent;
        }
        self.put(i, e);
    }

    fn sift_down(&mut self, mut i: usize) {
        let n = self.v.len();
        let e = self.v[i];
        loop {
            let first = 4 * i + 1;
            if first >= n {
                break;
            }
            let mut best = first;
            for k in first + 1..(first + 4).min(n) {
                if self.v[k].0 < self.v[best].0 {
                    best = k;
                }
            }
            if self.v[best].0 >= e.0 {
                break;
            }
            self.put(i, self.v[best]);
            i = best;
        }
        self.put(i, e);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn key(c: u64, id: u32) -> Key {
        Key { cost_bits: c, u: id, v: id + 1 }
    }

    proptest! {
        /// Any sequence of sets and removes, then pops: the keys come out
        /// in order, and they are each id's last key.
        #[test]
        fn pops_come_in_key_order(ops in proptest::collection::vec((0u32..40, 0u64..20, any::<bool>()), 0..300)) {
            let mut h = EdgeHeap::from(Vec::new(), 0);
            h.grow(40);
            let mut want: std::collections::BTreeMap<u32, Key> = Default::default();
            for (id, c, put) in ops {
                if put {
                    h.set(id, key(c, id));
                    want.insert(id, key(c, id));
                } else {
                    h.remove(id);
                    want.remove(&id);
                }
                prop_assert_eq!(h.len(), want.len());
            }
            let mut got = Vec::new();
            while let Some((k, id)) = h.peek() {
                prop_assert!(h.contains(id));
                h.remove(id);
                got.push((k, id));
            }
            let mut expected: Vec<(Key, u32)> = want.into_iter().map(|(id, k)| (k, id)).collect();
            expected.sort();
            prop_assert_eq!(got, expected);
        }
    }

    #[test]
    fn built_heap_pops_in_order() {
        let entries: Vec<(Key, u32)> = (0..100u32).map(|i| (key(((i * 37) % 100) as u64, i), i)).collect();
        let mut h = EdgeHeap::from(entries, 100);
        let mut last = None;
        while let Some((k, id)) = h.peek() {
            h.remove(id);
            assert!(last < Some(k));
            last = Some(k);
        }
    }
}
