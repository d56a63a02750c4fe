//! Path storage with pruning: the trajectories of the living particles, and nothing else.
//!
//! [`Genealogy`](crate::genealogy::Genealogy) keeps every ancestor index of every step
//! (`N·n` of them), which a genealogy *plot* needs because it draws the dead branches too.
//! A path-space estimate only needs the ancestry of the particles alive now. This tree holds
//! one node per state still on some living particle's path: when a particle leaves no
//! offspring, its node is freed, and so is every ancestor whose last child that was. Because
//! lineages coalesce (Cappé & Moulines, Fig. 1), the tree is a long single trunk plus a
//! bush of depth `O(N)`-ish near the present: for a mixing model its size stays near
//! `n + c·N·log N` (Jacob, Murray & Rubenthaler, 2015) instead of `N·n`.
//!
//! Freed nodes go on a free list and are reused, so after the first steps a step allocates
//! nothing.

use crate::error::{CoreError, Result};
use crate::params::ParamError;

const NONE: u32 = u32::MAX;

/// The pruned ancestral tree of a particle system, storing a value (the state) per node.
#[derive(Debug, Clone)]
pub struct AncestryTree<S> {
    /// Parent node of each node (`NONE` for the roots, the particles of step 0).
    parent: Vec<u32>,
    /// Number of live children of each node; a node with none that is not a leaf is freed.
    children: Vec<u32>,
    /// The state stored at each node.
    value: Vec<S>,
    /// Reusable node slots.
    free: Vec<u32>,
    /// Node of each current particle.
    leaves: Vec<u32>,
    new_leaves: Vec<u32>,
    steps: usize,
    live: usize,
    peak: usize,
}

impl<S: Clone> AncestryTree<S> {
    /// A tree whose step-0 particles hold `initial`.
    ///
    /// # Errors
    /// [`CoreError::Empty`] for no particles; [`CoreError::Param`] for more than
    /// `u32::MAX − 1` particles (node ids are 32-bit to halve the memory).
    pub fn new(initial: &[S]) -> Result<Self> {
        if initial.is_empty() {
            return Err(CoreError::Empty {
                what: "initial particles of an ancestry tree",
            });
        }
        if initial.len() >= NONE as usize {
            return Err(CoreError::Param(ParamError {
                name: "N",
                value: initial.len() as f64,
                reason: "an ancestry tree holds fewer than 2^32 - 1 particles",
            }));
        }
        let n = initial.len();
        Ok(AncestryTree {
            parent: vec![NONE; n],
            children: vec![0; n],
            value: initial.to_vec(),
            free: Vec::new(),
            leaves: (0..n as u32).collect(),
            new_leaves: vec![0; n],
            steps: 1,
            live: n,
            peak: n,
        })
    }

    /// Number of particles `N`.
    pub fn n_particles(&self) -> usize {
        self.leaves.len()
    }

    /// Number of steps recorded (the trajectories have this length).
    pub fn n_steps(&self) -> usize {
        self.steps
    }

    /// Nodes currently stored.
    pub fn live_nodes(&self) -> usize {
        self.live
    }

    /// The most nodes ever stored at once (the memory high-water mark, in nodes).
    pub fn peak_nodes(&self) -> usize {
        self.peak
    }

    /// Bytes per stored node: parent id, child count and the state.
    pub fn bytes_per_node() -> usize {
        2 * std::mem::size_of::<u32>() + std::mem::size_of::<S>()
    }

    /// Record the next step: particle `i` now holds `values[i]` and descends from the
    /// current particle `ancestors[i]` (`A_k^i`).
    ///
    /// # Errors
    /// Slices of the wrong length, or an ancestor index out of range; the tree is then
    /// unchanged.
    pub fn push(&mut self, ancestors: &[usize], values: &[S]) -> Result<()> {
        let n = self.leaves.len();
        for (what, len) in [
            ("ancestor vector", ancestors.len()),
            ("values", values.len()),
        ] {
            if len != n {
                return Err(CoreError::DimensionMismatch {
                    what,
                    expected: n,
                    got: len,
                });
            }
        }
        if let Some(bad) = ancestors.iter().position(|&a| a >= n) {
            return Err(CoreError::Param(ParamError {
                name: "ancestor index",
                value: bad as f64,
                reason: "ancestor index out of range at this position",
            }));
        }
        for i in 0..n {
            let p = self.leaves[ancestors[i]];
            self.children[p as usize] += 1;
            let node = self.alloc(p, values[i].clone());
            self.new_leaves[i] = node;
        }
        // Old leaves without offspring die, and with them every ancestor left childless.
        for i in 0..n {
            let mut node = self.leaves[i];
            while node != NONE && self.children[node as usize] == 0 {
                let p = self.parent[node as usize];
                self.release(node);
                if p != NONE {
                    self.children[p as usize] -= 1;
                }
                node = p;
            }
        }
        std::mem::swap(&mut self.leaves, &mut self.new_leaves);
        self.steps += 1;
        Ok(())
    }

    fn alloc(&mut self, parent: u32, value: S) -> u32 {
        self.live += 1;
        self.peak = self.peak.max(self.live);
        match self.free.pop() {
            Some(slot) => {
                let s = slot as usize;
                self.parent[s] = parent;
                self.children[s] = 0;
                self.value[s] = value;
                slot
            }
            None => {
                self.parent.push(parent);
                self.children.push(0);
                self.value.push(value);
                (self.parent.len() - 1) as u32
            }
        }
    }

    fn release(&mut self, node: u32) {
        // Marked childless-and-free; the child count of a freed slot is never read again
        // before `alloc` resets it.
        self.parent[node as usize] = NONE;
        self.free.push(node);
        self.live -= 1;
    }

    /// The trajectory `ξ_{0:k}^i` of current particle `i`, oldest state first.
    ///
    /// # Errors
    /// `i` out of range.
    pub fn trajectory(&self, i: usize) -> Result<Vec<S>> {
        let Some(&leaf) = self.leaves.get(i) else {
            return Err(CoreError::DimensionMismatch {
                what: "particle of a trajectory (must be < N)",
                expected: self.leaves.len(),
                got: i,
            });
        };
        let mut out = Vec::with_capacity(self.steps);
        let mut node = leaf;
        while node != NONE {
            out.push(self.value[node as usize].clone());
            node = self.parent[node as usize];
        }
        out.reverse();
        Ok(out)
    }

    /// Number of distinct ancestors, at each of the last `depth` steps, of the current
    /// particles, most recent step last. A value of 1 means the paths have coalesced there.
    pub fn distinct_ancestors(&self, depth: usize) -> Vec<usize> {
        let depth = depth.min(self.steps);
        let mut level: Vec<u32> = self.leaves.clone();
        let mut counts = Vec::with_capacity(depth);
        for _ in 0..depth {
            level.sort_unstable();
            level.dedup();
            counts.push(level.len());
            level = level
                .iter()
                .map(|&n| self.parent[n as usize])
                .filter(|&p| p != NONE)
                .collect();
        }
        counts.reverse();
        counts
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::genealogy::Genealogy;
    use crate::mc::stream_rng;
    use rand::RngExt;

    #[test]
    fn trajectories_match_the_full_genealogy_and_dead_branches_are_freed() {
        let n = 40;
        let mut rng = stream_rng(5, 0);
        let mut positions: Vec<Vec<f64>> = vec![(0..n).map(|i| i as f64).collect()];
        let mut tree = AncestryTree::new(&positions[0]).unwrap();
        let mut full = Genealogy::new(n);
        full.push(&(0..n).collect::<Vec<_>>()).unwrap();
        for k in 1..200 {
            // Multinomial-like ancestors biased to low indices, so lineages die quickly.
            let a: Vec<usize> = (0..n)
                .map(|_| {
                    let u: f64 = rng.random();
                    ((u * u) * n as f64) as usize
                })
                .collect();
            let v: Vec<f64> = (0..n).map(|i| (k * 1000 + i) as f64).collect();
            tree.push(&a, &v).unwrap();
            full.push(&a).unwrap();
            positions.push(v);
        }
        for i in 0..n {
            assert_eq!(
                tree.trajectory(i).unwrap(),
                full.trajectory(199, i, &positions).unwrap()
            );
        }
        // Live nodes are exactly the distinct (step, index) pairs on surviving paths.
        let on_paths: usize = full
            .alive_per_step()
            .iter()
            .map(|a| a.iter().filter(|&&b| b).count())
            .sum();
        assert_eq!(tree.live_nodes(), on_paths);
        assert!(
            tree.live_nodes() < n * 200 / 4,
            "pruned: {}",
            tree.live_nodes()
        );
        assert_eq!(
            tree.distinct_ancestors(200),
            full.surviving_counts(),
            "coalescence read off the pruned tree"
        );
    }

    #[test]
    fn without_resampling_nothing_is_freed_and_bad_input_changes_nothing() {
        let mut tree = AncestryTree::new(&[0.0, 1.0]).unwrap();
        tree.push(&[0, 1], &[2.0, 3.0]).unwrap();
        assert_eq!(tree.live_nodes(), 4);
        assert!(tree.push(&[0], &[1.0, 2.0]).is_err());
        assert!(tree.push(&[0, 2], &[1.0, 2.0]).is_err());
        assert!(tree.push(&[0, 1], &[1.0]).is_err());
        assert_eq!(tree.n_steps(), 2);
        assert_eq!(tree.trajectory(1).unwrap(), vec![1.0, 3.0]);
        assert!(tree.trajectory(2).is_err());
        assert!(AncestryTree::<f64>::new(&[]).is_err());
    }
}
