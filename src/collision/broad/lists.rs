//! The cloth–cloth pair lists the broad phase keeps between searches (`BroadPhase`'s doc): what
//! a list holds, how far its boxes are grown, and when one is found at all.

use rayon::prelude::*;

use super::{merged, BroadPhase, Candidate, VF};
use crate::collision::bvh::Aabb;
use crate::math::{Real, PAR_GRAIN};

/// The cloth–cloth candidates of a search whose points' boxes were grown by the reach
/// (`BroadPhase` doc), in the search's order, with the grown boxes.
pub(super) struct PairList {
    pub(super) cloth: Vec<Aabb>,
    /// Whether the growth is small beside the edges (`tight`); a list is found only then.
    pub(super) tight: bool,
    /// None while the searches are made from the trees (`SERVED`): the grown boxes then only
    /// tell whether a list would have served.
    pub(super) candidates: Option<Vec<Candidate>>,
    /// The searches the boxes have held for.
    pub(super) served: usize,
    /// Of those, the ones served from `candidates`, and the seconds they and finding the list
    /// took.
    pub(super) listed: usize,
    pub(super) spent: f64,
}

impl PairList {
    /// Whether every point's box lies within the one the list was found for.
    pub(super) fn holds(&self, cloth: &[Aabb]) -> bool {
        self.cloth.len() == cloth.len()
            && self
                .cloth
                .par_iter()
                .with_min_len(PAR_GRAIN)
                .zip(cloth)
                .all(|(k, b)| (0..3).all(|j| k.min[j] <= b.min[j] && b.max[j] <= k.max[j]))
    }
}

/// The pair list of one pad (the proximity search's, the collision iterations') and what lists
/// and tree searches have cost, each search timed whole (its cloth–obstacle pairs included).
/// Where the points move farther than their growth between searches, or the grown boxes take
/// in many more pairs than the narrow phase keeps (a coarse dress on a dancer: 100k–200k
/// cloth–cloth candidates, a handful of contacts), a list costs more than the tree searches it
/// replaces; so a list is found only where the growth is tight and its boxes have held for
/// `SERVED` searches, and after a list has served, its cost per search (finding it included)
/// is set against the trees' (measured on the searches made from the trees): after a
/// list that loses, none is found for `FIRST_WAIT` searches times the ratio of the two costs,
/// then twice as long times the ratio after each further loss, up to `LONGEST_WAIT` (a list of
/// 1.2 M candidates on ARCSim's dress-blue took 250 ms to find, against 5–10 ms for a search
/// from the trees). The choice changes only the time taken, never the pairs (struct doc).
pub(super) struct ListSlot {
    pub(super) pad: u64,
    pub(super) list: Option<PairList>,
    /// Seconds per search from the trees (a moving average; infinite until measured).
    pub(super) tree_s: f64,
    /// The wait after the last loss, and the searches left of it.
    pub(super) wait: usize,
    pub(super) skip: usize,
}

/// The searches without a list after one has lost to the trees by a ratio of 1, the first
/// time, and at most (a dress on a dancer makes 50–100 searches of each pad a frame).
const FIRST_WAIT: usize = 16;
const LONGEST_WAIT: usize = 1 << 16;

/// How far a point's box `span` (over a search's interval) is grown for a kept list: `AHEAD`
/// times the point's travel over the interval, plus `reach`.
pub(super) fn grown(span: &Aabb, reach: Real) -> Real {
    AHEAD * (span.max - span.min).max() + reach
}

/// Whether the nodes' boxes grown by `growth` take in few more pairs than they hold now: the
/// mean growth at most `TIGHT` times the mean extent of the edges' boxes. A list's candidates
/// grow with the boxes' volume (ARCSim's dress-blue at its step's travel: 1.2 M candidates,
/// 250 ms to find, against 5–10 ms for a search from the trees).
pub(super) fn tight(growth: &[Real], cloth: &[Aabb], edges: &[[usize; 2]]) -> bool {
    let extent: Real = edges.iter().map(|e| merged(cloth, e)).map(|b| (b.max - b.min).max()).sum();
    let grown: Real = growth.iter().sum();
    !edges.is_empty() && grown / growth.len() as Real <= TIGHT * extent / edges.len() as Real
}

/// See `tight`.
const TIGHT: Real = 0.25;

/// How many more intervals like the one a list is found over a point's grown box covers at
/// its travel over it (`grown`).
const AHEAD: Real = 3.0;

/// A list is found within grown boxes that have held for this many searches (`ListSlot`).
pub(super) const SERVED: usize = 3;

/// The box test of candidate `c` (`box_of` each of its points' boxes): the one the tree search
/// applies at its leaves, for every kind of pair: the target's box (face, or second edge)
/// against the query's (node, or first edge) inflated by `pad`.
pub(super) fn overlap<'a>((kind, c): &Candidate, pad: Real, box_of: impl Fn(usize) -> &'a Aabb) -> bool {
    let join = |ids: &[usize]| ids.iter().fold(Aabb::empty(), |a, &i| a.merge(box_of(i)));
    match *kind {
        VF => join(&c[1..]).overlaps(&box_of(c[0]).inflate(pad)),
        _ => join(&c[2..]).overlaps(&join(&c[..2]).inflate(pad)),
    }
}

impl BroadPhase {
    /// Whether a list is found for slot `k` now (`ListSlot`).
    pub(super) fn keeps(&self, k: usize) -> bool {
        self.forced() || self.lists[k].skip == 0
    }

    /// Whether lists are kept wherever the boxes hold (a test's choice; never in a run).
    pub(super) fn forced(&self) -> bool {
        #[cfg(test)]
        return self.always_keep;
        #[cfg(not(test))]
        false
    }

    /// Judges slot `k`'s last list, which no longer holds (`ListSlot`): whether the next is to be
    /// found at once (the last one was, and cost less per search than the trees).
    pub(super) fn judge(&mut self, k: usize, last: Option<&PairList>) -> bool {
        if self.forced() {
            return true;
        }
        let slot = &mut self.lists[k];
        let Some(last) = last else { return false };
        if last.listed == 0 {
            return false;
        }
        // The list's cost per search against the trees' (finding it included).
        let ratio = last.spent / last.listed as f64 / slot.tree_s;
        (slot.wait, slot.skip) = match ratio <= 1.0 {
            true => (0, 0),
            false => {
                let w = (2.0 * ratio * slot.wait.max(FIRST_WAIT / 2) as f64).min(LONGEST_WAIT as f64) as usize;
                (w, w)
            }
        };
        self.keeps(k)
    }
}
