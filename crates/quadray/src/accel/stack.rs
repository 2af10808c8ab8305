//! Traversal stacks, reused across rays: obvhs' own stacks are zeroed on every traversal, which
//! showed up as 5% of all instructions in profiles.

use std::cell::{Cell, RefCell};
use std::thread::LocalKey;

/// One thread's stacks of one kind: the first for a traversal, and spares for traversals that
/// run inside it (a level's top reaching an instance whose level has a top of its own).
pub(crate) struct Stacks<T> {
    first: RefCell<Vec<T>>,
    nested: RefCell<Vec<Vec<T>>>,
}

impl<T> Stacks<T> {
    /// No stacks yet.
    pub(crate) const fn new() -> Stacks<T> {
        Stacks {
            first: RefCell::new(Vec::new()),
            nested: RefCell::new(Vec::new()),
        }
    }
}

/// Runs `f` with an empty stack of this thread's `key`: the first one, or for a nested traversal
/// a spare taken and returned, so no traversal allocates once the stacks have grown (measured:
/// taking every stack from a pool instead cost 15% of a frame of scenes/reflective.toml).
#[inline]
pub(crate) fn with_stack<T, R>(
    key: &'static std::thread::LocalKey<Stacks<T>>,
    f: impl FnOnce(&mut Vec<T>) -> R,
) -> R {
    key.with(|stacks| match stacks.first.try_borrow_mut() {
        Ok(mut stack) => {
            stack.clear();
            f(&mut stack)
        }
        Err(_) => {
            let mut stack = stacks.nested.borrow_mut().pop().unwrap_or_default();
            stack.clear();
            let result = f(&mut stack);
            stacks.nested.borrow_mut().push(stack);
            result
        }
    })
}

/// An empty stack of this thread's `key`, taken out of its spares (a new one when there are none),
/// for a traversal that must not run in a closure: a closure is compiled with the target features
/// of the function it is written in, so the AVX2 path's traversal in [`with_stack`]'s closure ran
/// without AVX2. Give it back with [`put_stack`].
#[inline(always)]
pub(crate) fn take_stack<T>(key: &'static LocalKey<Stacks<T>>) -> Vec<T> {
    let mut stack = key
        .with(|stacks| stacks.nested.borrow_mut().pop())
        .unwrap_or_default();
    stack.clear();
    stack
}

/// Returns a stack from [`take_stack`] to this thread's spares of `key`.
#[inline(always)]
pub(crate) fn put_stack<T>(key: &'static LocalKey<Stacks<T>>, stack: Vec<T>) {
    key.with(|stacks| stacks.nested.borrow_mut().push(stack));
}

/// This thread's cell of `key`, for a traversal that never runs inside another of its kind to
/// take its stack out of (`Cell::take`, then empty it) and set it back (`Cell::set`); a nested
/// one would find an empty vector there, which is still correct.
///
/// Not lent to a closure (as [`with_stack`] lends): a closure is compiled with the target
/// features of the function it is written in, so the mesh traversal in it ran without AVX2 on
/// the AVX2 path unless inlined, and inlining through `LocalKey::with` was not reliable. And the
/// cell is looked up once a traversal: `key.take()` and `key.set()` each checked the
/// thread-local's lazy set-up, about 50 instructions a ray together.
#[inline(always)]
pub(crate) fn local_cell<T>(key: &'static LocalKey<Cell<Vec<T>>>) -> &'static Cell<Vec<T>> {
    // SAFETY: a thread-local lives until its thread ends, and `&Cell` is not `Send`, so the
    // reference cannot leave the thread; callers use it within one traversal (never from another
    // thread-local's destructor, when this one may be gone).
    key.with(|cell| unsafe { &*(cell as *const Cell<Vec<T>>) })
}
