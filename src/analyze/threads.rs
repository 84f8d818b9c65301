//! Starting threads: every thread of the pipeline and its renderers is
//! started here, so a system out of threads is met in one place (and tests
//! can make it so).

use std::thread::Scope;

/// Starts `f` on a new thread of `scope`; `false` when the system will not
/// start one (out of threads or memory). Every thread of the pipeline and
/// its renderers starts here, and a caller told `false` goes on with the
/// threads it has, at least its own: a run never fails for want of a thread.
pub(crate) fn spawn_scoped<'scope, 'env, F>(scope: &'scope Scope<'scope, 'env>, f: F) -> bool
where
    F: FnOnce() + Send + 'scope,
{
    if spawn_limit::refused() {
        return false;
    }
    std::thread::Builder::new().spawn_scoped(scope, f).is_ok()
}

/// Tests make spawning fail: after `allow(n)`, the next `n` spawns from
/// this thread start, the ones after fail, as when the system is out of
/// threads.
#[cfg(test)]
pub(crate) mod spawn_limit {
    use std::cell::Cell;

    thread_local! {
        static LEFT: Cell<Option<usize>> = const { Cell::new(None) };
    }

    /// Lets `n` more spawns from this thread start (`None`: no limit).
    pub(crate) fn allow(n: Option<usize>) {
        LEFT.with(|left| left.set(n));
    }

    pub(super) fn refused() -> bool {
        LEFT.with(|left| match left.get() {
            None => false,
            Some(0) => true,
            Some(n) => {
                left.set(Some(n - 1));
                false
            }
        })
    }
}

#[cfg(not(test))]
mod spawn_limit {
    pub(super) fn refused() -> bool {
        false
    }
}
