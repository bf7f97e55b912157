//! The MPI ranks of a command (cargo feature `mpi`), or a single rank without it.
//!
//! Every collective step goes through [`Ranks::agree`]: each rank brings its own outcome, and
//! either every rank goes on or every rank stops, the lowest failing rank printing its message
//! before any rank exits ([`Reported`]), so bad input or a failed member on one rank never
//! leaves the others waiting, and its message is not lost when mpirun ends the job at the first
//! non-zero exit. A panic on any rank aborts all of them.

use anyhow::{Result, bail};
use colloidsim_core::exchange::Exchange;

/// A rank failed and has printed why on stderr; every rank stops without another message.
#[derive(Debug, thiserror::Error)]
#[error("rank {0} failed (its message is above)")]
pub struct Reported(pub usize);

/// The ranks of this process's job.
pub struct Ranks {
    rank: usize,
    size: usize,
    local: usize,
    #[cfg(feature = "mpi")]
    world: mpi::topology::SimpleCommunicator,
    #[cfg(feature = "mpi")]
    _universe: mpi::environment::Universe,
}

/// The number of ranks a launcher (mpirun, srun) says this process belongs to, if any.
#[cfg(not(feature = "mpi"))]
fn launched_size() -> Option<usize> {
    [
        "OMPI_COMM_WORLD_SIZE",
        "PMI_SIZE",
        "PMIX_SIZE",
        "SLURM_NTASKS",
    ]
    .iter()
    .find_map(|v| std::env::var(v).ok()?.parse().ok())
}

impl Ranks {
    /// Join the job's ranks (one rank when not launched by mpirun).
    #[cfg(feature = "mpi")]
    pub fn init() -> Result<Self> {
        use mpi::traits::Communicator;
        // A decomposed run calls MPI from the thread that steps it, one call at a time.
        let Some((universe, _)) = mpi::initialize_with_threading(mpi::Threading::Serialized) else {
            bail!("MPI was initialised twice");
        };
        let world = universe.world();
        let local = world.split_shared(0).size() as usize;
        let ranks = Self {
            rank: world.rank() as usize,
            size: world.size() as usize,
            local,
            world,
            _universe: universe,
        };
        if ranks.size > 1 {
            let default = std::panic::take_hook();
            std::panic::set_hook(Box::new(move |info| {
                default(info);
                mpi::topology::SimpleCommunicator::world().abort(70);
            }));
        }
        Ok(ranks)
    }

    /// One rank; refused when a launcher started several copies of this MPI-less build.
    #[cfg(not(feature = "mpi"))]
    pub fn init() -> Result<Self> {
        if let Some(n) = launched_size().filter(|&n| n > 1) {
            bail!(
                "started as one of {n} MPI ranks, but this colloidsim was built without MPI: \
                 build it with `cargo build --release --features mpi` (docs/parallel.md)"
            );
        }
        Ok(Self {
            rank: 0,
            size: 1,
            local: 1,
        })
    }

    /// This rank (0 ..< size).
    pub fn rank(&self) -> usize {
        self.rank
    }

    /// The number of ranks.
    pub fn size(&self) -> usize {
        self.size
    }

    /// Worker threads per rank when `--threads` is not given: the cores shared by the ranks on
    /// this node (all cores with one rank).
    pub fn default_threads(&self) -> Option<usize> {
        if self.local <= 1 {
            return None;
        }
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        Some((cores / self.local).max(1))
    }

    /// Go on together or stop together: `Ok` on every rank when `local` is `Ok` on every rank.
    /// Otherwise, on one rank, its error; on several, the lowest failing rank prints its error
    /// and, only once it has, every rank returns [`Reported`]: mpirun ends the whole job at the
    /// first rank that exits non-zero, which must not come before the message.
    pub fn agree<T>(&self, local: Result<T>) -> Result<T> {
        let mine = if local.is_err() { self.rank } else { self.size };
        let first = self.min(mine);
        match local {
            Ok(v) if first == self.size => Ok(v),
            Err(e) if self.size == 1 => Err(e),
            local => {
                if let Err(e) = &local
                    && first == self.rank
                {
                    crate::report(e);
                }
                self.barrier();
                Err(Reported(first).into())
            }
        }
    }

    /// Wait until every rank is here.
    #[cfg(feature = "mpi")]
    fn barrier(&self) {
        use mpi::collective::CommunicatorCollectives;
        self.world.barrier();
    }

    #[cfg(not(feature = "mpi"))]
    fn barrier(&self) {}

    /// The smallest of every rank's `x`.
    #[cfg(feature = "mpi")]
    fn min(&self, x: usize) -> usize {
        use mpi::collective::{CommunicatorCollectives, SystemOperation};
        let mut out = 0u64;
        self.world
            .all_reduce_into(&(x as u64), &mut out, SystemOperation::min());
        out as usize
    }

    #[cfg(not(feature = "mpi"))]
    fn min(&self, x: usize) -> usize {
        x
    }

    /// The ranks as a run decomposed in space talks over them.
    #[cfg(feature = "mpi")]
    pub fn exchange(&self) -> Result<Box<dyn Exchange>> {
        let level = mpi::environment::threading_support();
        if level < mpi::Threading::Serialized {
            bail!(
                "this MPI library gives threading level {level:?}; a decomposed run needs at least \
                 Serialized (MPI_THREAD_SERIALIZED)"
            );
        }
        Ok(Box::new(MpiExchange))
    }

    #[cfg(not(feature = "mpi"))]
    pub fn exchange(&self) -> Result<Box<dyn Exchange>> {
        bail!("this colloidsim was built without MPI")
    }

    /// Every rank's `text`, in rank order, on every rank.
    #[cfg(feature = "mpi")]
    pub fn all_gather(&self, text: &str) -> Vec<String> {
        let mut buf = Vec::new();
        let counts = all_gather_varcount(text.as_bytes(), &mut buf);
        let mut start = 0;
        counts
            .iter()
            .map(|&c| {
                let part = &buf[start..start + c];
                start += c;
                String::from_utf8_lossy(part).into_owned()
            })
            .collect()
    }

    #[cfg(not(feature = "mpi"))]
    pub fn all_gather(&self, text: &str) -> Vec<String> {
        vec![text.to_string()]
    }
}

/// Every rank's `mine`, concatenated in rank order, into `all` on every rank; the lengths.
#[cfg(feature = "mpi")]
fn all_gather_varcount<T: mpi::datatype::Equivalence + Copy + Default>(
    mine: &[T],
    all: &mut Vec<T>,
) -> Vec<usize> {
    use mpi::collective::CommunicatorCollectives;
    use mpi::datatype::PartitionMut;
    use mpi::traits::Communicator;
    let world = mpi::topology::SimpleCommunicator::world();
    let mut counts = vec![0i32; world.size() as usize];
    world.all_gather_into(&(mine.len() as i32), &mut counts[..]);
    let displs: Vec<i32> = counts
        .iter()
        .scan(0, |acc, &c| {
            let d = *acc;
            *acc += c;
            Some(d)
        })
        .collect();
    all.clear();
    all.resize(counts.iter().map(|&c| c as usize).sum(), T::default());
    let mut part = PartitionMut::new(&mut all[..], &counts[..], &displs[..]);
    world.all_gather_varcount_into(mine, &mut part);
    counts.iter().map(|&c| c as usize).collect()
}

/// The engines' [`Exchange`] over MPI's world communicator (MPI at level Serialized, checked
/// in [`Ranks::exchange`]: a run makes its calls one at a time, from whichever thread steps
/// it). Collectives meet in call order, which every rank shares, so the run's messages never
/// mix with [`Ranks`]'s.
#[cfg(feature = "mpi")]
struct MpiExchange;

#[cfg(feature = "mpi")]
impl MpiExchange {
    fn world() -> mpi::topology::SimpleCommunicator {
        mpi::topology::SimpleCommunicator::world()
    }
}

#[cfg(feature = "mpi")]
impl Exchange for MpiExchange {
    fn rank(&self) -> usize {
        use mpi::traits::Communicator;
        Self::world().rank() as usize
    }

    fn size(&self) -> usize {
        use mpi::traits::Communicator;
        Self::world().size() as usize
    }

    fn shift(&self, to: usize, send: &[f64], from: usize, recv: &mut Vec<f64>) {
        use mpi::point_to_point::send_receive_into;
        use mpi::traits::Communicator;
        let world = Self::world();
        let (dest, source) = (
            world.process_at_rank(to as i32),
            world.process_at_rank(from as i32),
        );
        // The length first, then the numbers.
        let mut n = 0u64;
        send_receive_into(&(send.len() as u64), &dest, &mut n, &source);
        recv.clear();
        recv.resize(n as usize, 0.0);
        send_receive_into(send, &dest, &mut recv[..], &source);
    }

    fn all_gather(&self, mine: &[f64], all: &mut Vec<f64>) {
        all_gather_varcount(mine, all);
    }

    fn all_gather_same(&self, mine: &[f64], all: &mut Vec<f64>) {
        use mpi::collective::CommunicatorCollectives;
        let world = Self::world();
        all.clear();
        all.resize(mine.len() * self.size(), 0.0);
        world.all_gather_into(mine, &mut all[..]);
    }

    fn shift_exact(&self, to: usize, send: &[f64], from: usize, recv: &mut [f64]) {
        use mpi::point_to_point::send_receive_into;
        use mpi::traits::Communicator;
        let world = Self::world();
        let (dest, source) = (
            world.process_at_rank(to as i32),
            world.process_at_rank(from as i32),
        );
        send_receive_into(send, &dest, recv, &source);
    }

    fn all_gather_and_shift(
        &self,
        (mine, all): (&[f64], &mut Vec<f64>),
        to: usize,
        send: &[f64],
        from: usize,
        recv: &mut [f64],
    ) {
        use mpi::collective::CommunicatorCollectives;
        use mpi::point_to_point::send_receive_into;
        use mpi::traits::Communicator;
        let world = Self::world();
        all.clear();
        all.resize(mine.len() * self.size(), 0.0);
        let (dest, source) = (
            world.process_at_rank(to as i32),
            world.process_at_rank(from as i32),
        );
        // The all-gather progresses while the shift waits for its message.
        mpi::request::scope(|scope| {
            let gather = world.immediate_all_gather_into(scope, mine, &mut all[..]);
            send_receive_into(send, &dest, recv, &source);
            gather.wait();
        });
    }

    fn abort(&self, message: &str) -> ! {
        use mpi::traits::Communicator;
        eprintln!("error: {message}");
        Self::world().abort(1)
    }
}

#[cfg(all(test, not(feature = "mpi")))]
mod tests {
    use super::*;

    #[test]
    fn one_rank_agrees_with_itself() {
        let r = Ranks {
            rank: 0,
            size: 1,
            local: 1,
        };
        assert_eq!(r.agree(Ok(3)).unwrap(), 3);
        let e = r.agree::<()>(Err(anyhow::anyhow!("bad key"))).unwrap_err();
        assert_eq!(e.to_string(), "bad key");
        assert_eq!(r.all_gather("x"), ["x"]);
    }
}
