//! Helpers shared by unit tests that need MPI.

use std::sync::{Mutex, OnceLock, PoisonError};

use mpi::environment::Universe;
use mpi::topology::SimpleCommunicator;
use mpi::Threading;

/// Runs `f` on a one-process communicator. MPI is initialised once per
/// test process and kept (MPI cannot be initialised twice); the tests
/// that use it run one at a time.
pub fn on_one_rank<R>(f: impl FnOnce(&SimpleCommunicator) -> R) -> R {
    static LOCK: Mutex<()> = Mutex::new(());
    static UNIVERSE: OnceLock<Universe> = OnceLock::new();
    let _one_at_a_time = LOCK.lock().unwrap_or_else(PoisonError::into_inner);
    UNIVERSE.get_or_init(|| {
        mpi::initialize_with_threading(Threading::Serialized)
            .expect("MPI initialises")
            .0
    });
    f(&SimpleCommunicator::self_comm())
}
