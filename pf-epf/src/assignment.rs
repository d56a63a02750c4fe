//! Optimal assignment (Kuhn–Munkres, the O(n²m) shortest-augmenting-path form) on a
//! rectangular cost matrix, with reusable buffers. Used for the global energy minimisation
//! of the association and for OSPA.

/// The Hungarian method's potentials and path buffers, kept between calls.
#[derive(Debug, Clone, Default)]
pub struct Hungarian {
    u: Vec<f64>,
    v: Vec<f64>,
    p: Vec<usize>,
    way: Vec<usize>,
    minv: Vec<f64>,
    used: Vec<bool>,
}

impl Hungarian {
    /// Fresh buffers.
    pub fn new() -> Self {
        Self::default()
    }

    /// Assign each of `n` rows to a distinct one of `m ≥ n` columns minimising the total of
    /// `cost[i·m + j]` (finite values); writes the column of row `i` into `row_to_col[i]`
    /// and returns the total cost. Returns `None` if `n > m`, the shapes disagree, or a cost
    /// is not finite.
    pub fn solve(
        &mut self,
        n: usize,
        m: usize,
        cost: &[f64],
        row_to_col: &mut [usize],
    ) -> Option<f64> {
        if n > m
            || cost.len() != n * m
            || row_to_col.len() != n
            || cost.iter().any(|c| !c.is_finite())
        {
            return None;
        }
        let a = |i: usize, j: usize| cost[(i - 1) * m + (j - 1)];
        for (buf, len) in [
            (&mut self.u, n + 1),
            (&mut self.v, m + 1),
            (&mut self.minv, m + 1),
        ] {
            buf.clear();
            buf.resize(len, 0.0);
        }
        self.p.clear();
        self.p.resize(m + 1, 0);
        self.way.clear();
        self.way.resize(m + 1, 0);
        self.used.clear();
        self.used.resize(m + 1, false);
        for i in 1..=n {
            self.p[0] = i;
            let mut j0 = 0;
            self.minv.fill(f64::INFINITY);
            self.used.fill(false);
            loop {
                self.used[j0] = true;
                let i0 = self.p[j0];
                let mut delta = f64::INFINITY;
                let mut j1 = 0;
                for j in 1..=m {
                    if !self.used[j] {
                        let cur = a(i0, j) - self.u[i0] - self.v[j];
                        if cur < self.minv[j] {
                            self.minv[j] = cur;
                            self.way[j] = j0;
                        }
                        if self.minv[j] < delta {
                            delta = self.minv[j];
                            j1 = j;
                        }
                    }
                }
                for j in 0..=m {
                    if self.used[j] {
                        self.u[self.p[j]] += delta;
                        self.v[j] -= delta;
                    } else {
                        self.minv[j] -= delta;
                    }
                }
                j0 = j1;
                if self.p[j0] == 0 {
                    break;
                }
            }
            loop {
                let j1 = self.way[j0];
                self.p[j0] = self.p[j1];
                j0 = j1;
                if j0 == 0 {
                    break;
                }
            }
        }
        let mut total = 0.0;
        for j in 1..=m {
            if self.p[j] != 0 {
                row_to_col[self.p[j] - 1] = j - 1;
                total += a(self.p[j], j);
            }
        }
        Some(total)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force over all injections of n rows into m columns.
    fn brute(n: usize, m: usize, cost: &[f64]) -> f64 {
        fn rec(i: usize, n: usize, m: usize, cost: &[f64], used: &mut Vec<bool>) -> f64 {
            if i == n {
                return 0.0;
            }
            let mut best = f64::INFINITY;
            for j in 0..m {
                if !used[j] {
                    used[j] = true;
                    best = best.min(cost[i * m + j] + rec(i + 1, n, m, cost, used));
                    used[j] = false;
                }
            }
            best
        }
        rec(0, n, m, cost, &mut vec![false; m])
    }

    #[test]
    fn matches_brute_force_on_random_rectangular_problems() {
        use rand::RngExt;
        let mut rng = pf_core::mc::stream_rng(11, 0);
        let mut h = Hungarian::new();
        for _ in 0..200 {
            let n = rng.random_range(1..5);
            let m = n + rng.random_range(0..3);
            let cost: Vec<f64> = (0..n * m).map(|_| rng.random_range(0.0..10.0)).collect();
            let mut out = vec![0; n];
            let total = h.solve(n, m, &cost, &mut out).unwrap();
            // Exact to rounding of a sum of ≤ 4 terms of size ≤ 10.
            assert!((total - brute(n, m, &cost)).abs() < 1e-9);
            let mut seen = out.clone();
            seen.sort_unstable();
            seen.dedup();
            assert_eq!(seen.len(), n, "columns must be distinct");
            let recomputed: f64 = out.iter().enumerate().map(|(i, &j)| cost[i * m + j]).sum();
            assert!((recomputed - total).abs() < 1e-9);
        }
    }

    #[test]
    fn rejects_bad_shapes() {
        let mut h = Hungarian::new();
        assert!(h.solve(2, 1, &[0.0, 0.0], &mut [0, 0]).is_none());
        assert!(h.solve(1, 2, &[0.0, f64::NAN], &mut [0]).is_none());
    }
}
