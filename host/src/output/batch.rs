//! All of a command's outputs, or none: while a [`Batch`] is open on a thread, every
//! file written there is synced to disk under a temporary name and renamed only when the
//! batch commits, after the last one was written. A failure on one output (a full disk
//! on the report) then leaves none of the others behind.

use std::cell::RefCell;

use anyhow::Result;

use super::target::Pending;

thread_local! {
    /// The open batch's outputs, written and synced, waiting for their names.
    static OPEN: RefCell<Option<Vec<Pending>>> = const { RefCell::new(None) };
}

/// An open batch; dropping it without [`Batch::commit`] discards its outputs.
pub struct Batch {
    /// False for a batch opened inside another: the outer one names or discards all.
    outermost: bool,
}

impl Batch {
    /// Opens a batch on this thread (one opened inside another joins it).
    pub fn begin() -> Batch {
        OPEN.with(|o| {
            let mut open = o.borrow_mut();
            let outermost = open.is_none();
            open.get_or_insert_with(Vec::new);
            Batch { outermost }
        })
    }

    /// Gives every output its name (an inner batch leaves that to the outer one).
    pub fn commit(mut self) -> Result<()> {
        if !self.outermost {
            return Ok(());
        }
        self.outermost = false;
        let pending = OPEN.with(|o| o.borrow_mut().take()).unwrap_or_default();
        pending.into_iter().try_for_each(Pending::rename)
    }
}

impl Drop for Batch {
    fn drop(&mut self) {
        // Dropping the pending files deletes their temporaries.
        if self.outermost {
            OPEN.with(|o| o.borrow_mut().take());
        }
    }
}

/// Finishes an output: synced and held if a batch is open, else synced and named now.
pub(crate) fn finish(mut file: Pending) -> Result<()> {
    file.sync()?;
    let held = OPEN.with(|o| match o.borrow_mut().as_mut() {
        Some(list) => {
            list.push(file);
            None
        }
        None => Some(file),
    });
    match held {
        Some(file) => file.rename(),
        None => Ok(()),
    }
}
