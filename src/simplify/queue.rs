//! An indexed binary max-heap of triangles: each triangle is in it at most once, with its current
//! key, so rescanning a triangle updates its entry in place instead of leaving a stale one (the
//! queue stays as small as the set of triangles above the bound).

const NOT_QUEUED: u32 = u32::MAX;

/// Max-heap of `(key << 32) | triangle` entries, with each triangle's position.
#[derive(Debug, Default)]
pub(super) struct TriangleQueue {
    heap: Vec<u64>,
    pos: Vec<u32>,
}

impl TriangleQueue {
    /// Sets triangle `t`'s key (`Some`), or takes it out of the queue (`None`).
    pub(super) fn set(&mut self, t: u32, key: Option<u32>) {
        if t as usize >= self.pos.len() {
            self.pos.resize(t as usize + 1, NOT_QUEUED);
        }
        let p = self.pos[t as usize];
        match (key, p) {
            (None, NOT_QUEUED) => {}
            (None, p) => self.remove_at(p as usize),
            (Some(k), NOT_QUEUED) => {
                let i = self.heap.len();
                self.heap.push(entry(k, t));
                self.pos[t as usize] = i as u32;
                self.up(i);
            }
            (Some(k), p) => {
                let i = p as usize;
                let old = self.heap[i];
                self.heap[i] = entry(k, t);
                if self.heap[i] > old {
                    self.up(i);
                } else {
                    self.down(i);
                }
            }
        }
    }

    /// The triangle with the largest key (ties: the largest id).
    pub(super) fn peek(&self) -> Option<u32> {
        self.heap.first().map(|&e| e as u32)
    }

    /// Removes the top triangle.
    pub(super) fn pop(&mut self) -> Option<u32> {
        let t = self.peek()?;
        self.remove_at(0);
        Some(t)
    }

    /// Number of queued triangles.
    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.heap.len()
    }

    fn remove_at(&mut self, i: usize) {
        let t = self.heap[i] as u32;
        self.pos[t as usize] = NOT_QUEUED;
        let last = self.heap.pop().expect("non-empty");
        if i < self.heap.len() {
            self.heap[i] = last;
            self.pos[last as u32 as usize] = i as u32;
            if last > self.heap.get(parent(i)).copied().unwrap_or(u64::MAX) && i > 0 {
                self.up(i);
            } else {
                self.down(i);
            }
        }
    }

    fn up(&mut self, mut i: usize) {
        let e = self.heap[i];
        while i > 0 {
            let p = parent(i);
            if self.heap[p] >= e {
                break;
            }
            self.heap[i] = self.heap[p];
            self.pos[self.heap[i] as u32 as usize] = i as u32;
            i = p;
        }
        self.heap[i] = e;
        self.pos[e as u32 as usize] = i as u32;
    }

    fn down(&mut self, mut i: usize) {
        let e = self.heap[i];
        let n = self.heap.len();
        loop {
            let l = 2 * i + 1;
            if l >= n {
                break;
            }
            let c = if l + 1 < n && self.heap[l + 1] > self.heap[l] {
                l + 1
            } else {
                l
            };
            if self.heap[c] <= e {
                break;
            }
            self.heap[i] = self.heap[c];
            self.pos[self.heap[i] as u32 as usize] = i as u32;
            i = c;
        }
        self.heap[i] = e;
        self.pos[e as u32 as usize] = i as u32;
    }
}

#[inline(always)]
fn parent(i: usize) -> usize {
    (i.wrapping_sub(1)) / 2
}

#[inline(always)]
fn entry(key: u32, t: u32) -> u64 {
    (u64::from(key) << 32) | u64::from(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn behaves_like_a_sorted_map() {
        let mut q = TriangleQueue::default();
        let mut model = std::collections::BTreeMap::new();
        let mut x = 12345u64;
        for _ in 0..20000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let t = (x % 300) as u32;
            let key = if x.is_multiple_of(5) {
                None
            } else {
                Some((x >> 20) as u32 % 1000)
            };
            q.set(t, key);
            match key {
                Some(k) => model.insert(t, k),
                None => model.remove(&t),
            };
            if x.is_multiple_of(7) {
                let want = model.iter().map(|(&t, &k)| (k, t)).max().map(|(_, t)| t);
                assert_eq!(q.pop(), want);
                if let Some(t) = want {
                    model.remove(&t);
                }
            }
            assert_eq!(q.len(), model.len());
        }
    }
}
