//! The in-memory FMU states this library handed out and has not freed.
//!
//! An FMU state (`fmi2FMUstate`, `fmi3FMUState`) is an opaque pointer that the importer hands back, and nothing in the C
//! API stops it from handing back another FMU's state (every FMU in a process shares the type),
//! one freed already, or garbage. So every state is a [`Snapshot`] (a tag, the GUID of the FMU
//! that made it, the copy of the instance) whose address is recorded here from the moment it is
//! handed out until it is freed, and a pointer that is not recorded as a live state of this
//! model is refused before anything reads through it. The record is process-wide behind a
//! mutex, and one per library: every FMU's binary links its own copy of the runtime. Only the
//! FMU state functions touch it; a step never does.

use super::guard::Handle;
use super::instance::Sim;
use super::{Function, Terms};
use crate::model::CoSimulation;
use std::any::TypeId;
use std::collections::BTreeMap;
use std::sync::{Mutex, MutexGuard};

/// `b"RFMUSNAP"`: first word of every snapshot, checked with the GUID on every use.
const TAG: u64 = u64::from_le_bytes(*b"RFMUSNAP");

/// What an FMU state handle of this runtime points to.
pub struct Snapshot<M> {
    tag: u64,
    guid: &'static str,
    pub sim: Sim<M>,
}

/// Which model made a live state: there may be several in one library (in tests).
struct Maker {
    model: TypeId,
    guid: &'static str,
}

/// Live states by address.
static LIVE: Mutex<BTreeMap<usize, Maker>> = Mutex::new(BTreeMap::new());

fn live() -> MutexGuard<'static, BTreeMap<usize, Maker>> {
    // A panic while it was held (caught at the C boundary) left the map itself consistent.
    LIVE.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Hands out a copy of `sim` as a new state of the FMU `guid`.
pub fn adopt<M: CoSimulation>(guid: &'static str, sim: Sim<M>) -> Handle {
    let state = Box::into_raw(Box::new(Snapshot { tag: TAG, guid, sim }));
    live().insert(
        state as usize,
        Maker {
            model: TypeId::of::<M>(),
            guid,
        },
    );
    state as Handle
}

fn check<M: CoSimulation>(
    terms: &Terms,
    live: &BTreeMap<usize, Maker>,
    guid: &str,
    state: Handle,
) -> Result<(), String> {
    let arg = terms.fmu_state;
    match live.get(&(state as usize)) {
        None => Err(format!(
            "{arg} {state:p} is not a live state of this FMU: this FMU's {} or {} did not make it \
             (it is another FMU's, or no state at all), or {} freed it already",
            terms.name(Function::GetFmuState),
            terms.name(Function::DeserializeFmuState),
            terms.name(Function::FreeFmuState)
        )),
        Some(maker) if maker.model != TypeId::of::<M>() || maker.guid != guid => Err(format!(
            "{arg} {state:p} is not a live state of this FMU: it belongs to the FMU with {} {}",
            terms.token, maker.guid
        )),
        Some(_) => {
            // SAFETY: recorded as a live Box<Snapshot<M>> made by `adopt` and not freed since.
            let snapshot = unsafe { &*(state as *const Snapshot<M>) };
            if snapshot.tag != TAG || snapshot.guid != guid {
                return Err(format!(
                    "{arg} {state:p} was overwritten by someone else (its tag or {} is damaged)",
                    terms.token
                ));
            }
            Ok(())
        }
    }
}

/// Runs `f` on the snapshot behind `state` if it is a live state of model `M` with `guid`;
/// otherwise says why not, without reading through the pointer. The record stays locked while
/// `f` runs, so that no other thread frees the state meanwhile: `f` must not call the importer
/// (no logging).
pub fn with<M: CoSimulation, R>(
    terms: &Terms,
    guid: &str,
    state: Handle,
    f: impl FnOnce(&mut Snapshot<M>) -> R,
) -> Result<R, String> {
    let live = live();
    check::<M>(terms, &live, guid, state)?;
    // SAFETY: `check` found it live and made by `adopt` for M; the lock keeps it so.
    let snapshot = unsafe { &mut *(state as *mut Snapshot<M>) };
    Ok(f(snapshot))
}

/// Frees the live state `state` of model `M` with `guid`, or says why it is no such state (and
/// frees nothing).
pub fn release<M: CoSimulation>(terms: &Terms, guid: &str, state: Handle) -> Result<(), String> {
    let mut live = live();
    check::<M>(terms, &live, guid, state)?;
    live.remove(&(state as usize));
    if live.is_empty() {
        // An emptied BTreeMap keeps its root node; drop it, so that a library unloaded after
        // its last state was freed leaves nothing allocated (valgrind's "definitely lost").
        *live = BTreeMap::new();
    }
    drop(live);
    // SAFETY: it was live, made by `adopt` as a Box<Snapshot<M>>, and is no longer recorded, so
    // it is freed once.
    drop(unsafe { Box::from_raw(state as *mut Snapshot<M>) });
    Ok(())
}
