//! Messages between the domains of a run decomposed in space: MPI ranks (the CLI's `mpi`
//! feature), or threads of one process ([`LocalRanks`], for tests and for trying a
//! decomposition without MPI).
//!
//! Every call is collective over the ranks it names and must be made by them in the same order:
//! a rank's messages to another arrive in the order sent (MPI's non-overtaking rule). All data
//! travel as `f64`: tags and image counts are integers below `2^53`, exact in an `f64`.

use std::sync::mpsc::{Receiver, Sender, channel};

/// The ranks of a decomposed run, as the engines see them.
pub trait Exchange: Send {
    /// This rank (`0 ..< size`).
    fn rank(&self) -> usize;
    /// The number of ranks.
    fn size(&self) -> usize;
    /// Send `send` to rank `to` and receive the message of rank `from` into `recv` (resized to
    /// it). Every rank calls it at once, so that the sends form a permutation (a shift).
    fn shift(&self, to: usize, send: &[f64], from: usize, recv: &mut Vec<f64>);
    /// Every rank's `mine`, concatenated in rank order, into `all` (on every rank).
    fn all_gather(&self, mine: &[f64], all: &mut Vec<f64>);
    /// [`Self::all_gather`] when every rank sends as many numbers (one message fewer).
    fn all_gather_same(&self, mine: &[f64], all: &mut Vec<f64>) {
        self.all_gather(mine, all);
    }
    /// [`Self::shift`] when the receiver knows the length: into `recv`, which must be as long
    /// as the message (one message fewer).
    fn shift_exact(&self, to: usize, send: &[f64], from: usize, recv: &mut [f64]) {
        let mut m = Vec::with_capacity(recv.len());
        self.shift(to, send, from, &mut m);
        assert_eq!(
            m.len(),
            recv.len(),
            "shift_exact: message of another length"
        );
        recv.copy_from_slice(&m);
    }
    /// [`Self::all_gather_same`] of `mine` into `all` and [`Self::shift_exact`] of `send` at
    /// once: an implementation may overlap the two (MPI: a non-blocking all-gather in flight
    /// during the shift), so that the ranks wait once instead of twice. By default one after
    /// the other.
    fn all_gather_and_shift(
        &self,
        (mine, all): (&[f64], &mut Vec<f64>),
        to: usize,
        send: &[f64],
        from: usize,
        recv: &mut [f64],
    ) {
        self.all_gather_same(mine, all);
        self.shift_exact(to, send, from, recv);
    }
    /// Stop every rank after a failure on this one alone (a file rank 0 could not write),
    /// which the others cannot learn of at their next message: print `error: message` and
    /// end the job (`MPI_Abort`; a panic for threads).
    fn abort(&self, message: &str) -> !;
}

/// Ranks that are threads of one process, talking over channels: [`LocalRanks::new`] gives one
/// endpoint per rank, each to be moved to its own thread.
pub struct LocalRanks {
    rank: usize,
    /// `to[r]` sends to rank `r`.
    to: Vec<Sender<Vec<f64>>>,
    /// `from[r]` receives what rank `r` sent here.
    from: Vec<Receiver<Vec<f64>>>,
}

impl LocalRanks {
    /// Endpoints for `size` ranks, in rank order.
    pub fn new(size: usize) -> Vec<LocalRanks> {
        assert!(size > 0, "at least one rank");
        // channel[a][b]: from a to b.
        let mut senders: Vec<Vec<Option<Sender<Vec<f64>>>>> = Vec::with_capacity(size);
        let mut receivers: Vec<Vec<Option<Receiver<Vec<f64>>>>> = (0..size)
            .map(|_| (0..size).map(|_| None).collect())
            .collect();
        for a in 0..size {
            let mut row = Vec::with_capacity(size);
            for rx_row in receivers.iter_mut() {
                let (tx, rx) = channel();
                row.push(Some(tx));
                rx_row[a] = Some(rx);
            }
            senders.push(row);
        }
        (0..size)
            .map(|r| LocalRanks {
                rank: r,
                to: senders[r].iter_mut().map(|s| s.take().unwrap()).collect(),
                from: receivers[r].iter_mut().map(|s| s.take().unwrap()).collect(),
            })
            .collect()
    }

    fn receive(&self, from: usize) -> Vec<f64> {
        self.from[from]
            .recv()
            .expect("a rank of LocalRanks stopped while others wait for it")
    }
}

impl Exchange for LocalRanks {
    fn abort(&self, message: &str) -> ! {
        panic!("rank {}: {message}", self.rank)
    }

    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.to.len()
    }

    fn shift(&self, to: usize, send: &[f64], from: usize, recv: &mut Vec<f64>) {
        // Unbounded channels: the send never blocks, so any permutation completes.
        self.to[to]
            .send(send.to_vec())
            .expect("a rank of LocalRanks stopped");
        let m = self.receive(from);
        recv.clear();
        recv.extend_from_slice(&m);
    }

    fn all_gather(&self, mine: &[f64], all: &mut Vec<f64>) {
        for (r, tx) in self.to.iter().enumerate() {
            if r != self.rank {
                tx.send(mine.to_vec())
                    .expect("a rank of LocalRanks stopped");
            }
        }
        all.clear();
        for r in 0..self.size() {
            if r == self.rank {
                all.extend_from_slice(mine);
            } else {
                all.extend_from_slice(&self.receive(r));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shifts_and_gathers_between_threads() {
        let ranks = LocalRanks::new(3);
        let out: Vec<(Vec<f64>, Vec<f64>)> = std::thread::scope(|s| {
            let handles: Vec<_> = ranks
                .into_iter()
                .map(|c| {
                    s.spawn(move || {
                        let r = c.rank();
                        let mut right = Vec::new();
                        // Send own rank to the left, receive the right neighbour's.
                        c.shift((r + 2) % 3, &[r as f64], (r + 1) % 3, &mut right);
                        let mut all = Vec::new();
                        c.all_gather(&vec![r as f64; r + 1], &mut all);
                        (right, all)
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        for (r, (right, all)) in out.iter().enumerate() {
            assert_eq!(right, &[((r + 1) % 3) as f64]);
            assert_eq!(all, &[0.0, 1.0, 1.0, 2.0, 2.0, 2.0]);
        }
    }
}
