//! Reading a planned list of ranges of a remote object ahead of the decoder: neighbouring ranges
//! coalesced into one request (up to [`MAX_REQUEST`]), [`super::io_concurrency`] requests in
//! flight on threads of their own, handed out in order; the memory held is bounded by the
//! requests in flight and done but not yet consumed.

use super::Source;
use std::collections::HashMap;
use std::io;
use std::sync::{Arc, Condvar, Mutex};

/// Ranges closer than this are read in one request (the gap's bytes are read and dropped): a
/// request costs a round trip, a few KiB cost less.
const COALESCE_GAP: u64 = 4 << 10;

/// The largest request made of several ranges (a range larger than this is one request).
const MAX_REQUEST: u64 = 8 << 20;

/// One request: the bytes `[at, at + len)`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Request {
    at: u64,
    len: u64,
}

#[derive(Default)]
struct State {
    /// The next request a thread may take.
    next: usize,
    /// The first request the reader still needs.
    consumed: usize,
    done: HashMap<usize, io::Result<Arc<Vec<u8>>>>,
    stop: bool,
}

struct Shared {
    state: Mutex<State>,
    cv: Condvar,
}

/// Ranges of one remote object read ahead (see the module's notes).
pub(crate) struct Ahead {
    source: Source,
    requests: Arc<Vec<Request>>,
    shared: Arc<Shared>,
    /// The request the last range came from, and its bytes.
    current: Option<(usize, Arc<Vec<u8>>)>,
    cursor: usize,
}

/// The requests that read `ranges` (offset, length; in reading order).
fn plan(ranges: &[(u64, u64)]) -> Vec<Request> {
    let mut out: Vec<Request> = Vec::new();
    for &(at, len) in ranges.iter().filter(|r| r.1 > 0) {
        if let Some(last) = out.last_mut() {
            let end = last.at + last.len;
            if at >= end && at - end <= COALESCE_GAP && at + len - last.at <= MAX_REQUEST {
                last.len = at + len - last.at;
                continue;
            }
        }
        out.push(Request { at, len });
    }
    out
}

impl Ahead {
    /// Starts reading `ranges` of `source` (in the order they will be asked for).
    pub(crate) fn new(source: &Source, ranges: &[(u64, u64)]) -> Ahead {
        let requests = Arc::new(plan(ranges));
        let shared = Arc::new(Shared {
            state: Mutex::new(State::default()),
            cv: Condvar::new(),
        });
        let threads = super::io_concurrency().min(requests.len());
        let window = 2 * super::io_concurrency();
        for _ in 0..threads {
            let (source, requests, shared) = (source.clone(), requests.clone(), shared.clone());
            std::thread::spawn(move || work(&source, &requests, &shared, window));
        }
        Ahead {
            source: source.clone(),
            requests,
            shared,
            current: None,
            cursor: 0,
        }
    }

    /// Fills `buf` with the bytes at `offset`: from the requests read ahead when the range is
    /// the next one planned, else read on its own.
    ///
    /// # Errors
    /// The request's error (the source's, naming what the server did).
    pub(crate) fn read(&mut self, offset: u64, buf: &mut [u8]) -> io::Result<()> {
        let end = offset + buf.len() as u64;
        let inside = |r: &Request| r.at <= offset && end <= r.at + r.len;
        let mut i = self.cursor;
        while i < self.requests.len() && self.requests[i].at + self.requests[i].len <= offset {
            i += 1;
        }
        if i >= self.requests.len() || !inside(&self.requests[i]) {
            return self.source.read_exact_at(offset, buf);
        }
        if self.current.as_ref().is_none_or(|(c, _)| *c != i) {
            self.current = None;
            let bytes = {
                let mut s = self.shared.state.lock().unwrap_or_else(|p| p.into_inner());
                s.consumed = i;
                self.shared.cv.notify_all();
                loop {
                    // Requests skipped over are dropped.
                    s.done.retain(|k, _| *k >= i);
                    if let Some(r) = s.done.remove(&i) {
                        break r;
                    }
                    s = self.shared.cv.wait(s).unwrap_or_else(|p| p.into_inner());
                }
            }?;
            self.current = Some((i, bytes));
        }
        self.cursor = i;
        let (_, bytes) = self.current.as_ref().expect("set above");
        let from = (offset - self.requests[i].at) as usize;
        buf.copy_from_slice(&bytes[from..from + buf.len()]);
        Ok(())
    }

    /// Whether `offset` starts a range this plan reads ahead (at or after the last one read).
    pub(crate) fn covers(&self, offset: u64) -> bool {
        self.requests[self.cursor.min(self.requests.len())..]
            .iter()
            .any(|r| r.at <= offset && offset < r.at + r.len)
    }
}

impl Drop for Ahead {
    fn drop(&mut self) {
        let mut s = self.shared.state.lock().unwrap_or_else(|p| p.into_inner());
        s.stop = true;
        s.done.clear();
        self.shared.cv.notify_all();
    }
}

/// A reading thread: takes the next request within `window` of the reader's, reads it, files
/// the result.
fn work(source: &Source, requests: &[Request], shared: &Shared, window: usize) {
    loop {
        let i = {
            let mut s = shared.state.lock().unwrap_or_else(|p| p.into_inner());
            loop {
                if s.stop || s.next >= requests.len() {
                    return;
                }
                if s.next < s.consumed {
                    s.next = s.consumed;
                }
                if s.next < s.consumed + window {
                    break;
                }
                s = shared.cv.wait(s).unwrap_or_else(|p| p.into_inner());
            }
            s.next += 1;
            s.next - 1
        };
        let r = requests[i];
        let mut bytes = vec![0u8; r.len as usize];
        let got = source
            .read_exact_at(r.at, &mut bytes)
            .map(|()| Arc::new(bytes));
        let mut s = shared.state.lock().unwrap_or_else(|p| p.into_inner());
        if !s.stop && i >= s.consumed {
            s.done.insert(i, got);
        }
        shared.cv.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn neighbouring_ranges_coalesce() {
        let r = plan(&[(100, 50), (150, 10), (4_000, 5), (200_000, 10), (0, 0)]);
        assert_eq!(
            r,
            [
                Request {
                    at: 100,
                    len: 3_905
                },
                Request {
                    at: 200_000,
                    len: 10
                }
            ]
        );
        // Never more than MAX_REQUEST in one, unless a range is larger by itself.
        let big = plan(&[
            (0, MAX_REQUEST - 10),
            (MAX_REQUEST - 10, 20),
            (MAX_REQUEST + 10, 1),
        ]);
        assert_eq!(big.len(), 2);
    }

    #[test]
    fn reads_in_order_and_out_of_plan() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.bin");
        let bytes: Vec<u8> = (0..500_000u32).map(|i| (i % 253) as u8).collect();
        std::fs::write(&p, &bytes).unwrap();
        let s = Source::open(&p).unwrap();
        let ranges: Vec<(u64, u64)> = (0..40).map(|i| (i * 12_000, 1000 + i)).collect();
        let mut a = Ahead::new(&s, &ranges);
        for &(at, len) in &ranges {
            let mut b = vec![0u8; len as usize];
            a.read(at, &mut b).unwrap();
            assert_eq!(b, bytes[at as usize..(at + len) as usize]);
        }
        let mut b = [0u8; 7];
        a.read(3, &mut b).unwrap();
        assert_eq!(b, bytes[3..10]);
    }
}
