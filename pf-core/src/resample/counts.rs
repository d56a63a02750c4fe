//! Offspring counts of the Poisson draws, a byte per particle.

/// Offspring counts, one byte per particle, with the rare counts of 255 or more (a particle
/// whose rate is above 12, or the last one taking a missing mass) marked [`Counts::BIG`] and
/// kept in a side list in particle order.
///
/// One pass writes the counts and the next reads them back, so at N = 10⁶, where they leave
/// the caches, bytes are one eighth of the memory traffic of `usize` counts: multinomial
/// resampling's counts and runs about 10 % faster.
#[derive(Debug, Default, Clone)]
pub(crate) struct Counts {
    /// Each particle's count, or [`Counts::BIG`].
    pub(crate) small: Vec<u8>,
    /// `(particle, count)` for every particle marked [`Counts::BIG`], ascending.
    pub(crate) big: Vec<(usize, usize)>,
    /// Each particle's whole run before removals, its base copies (residual resampling's
    /// floor `⌊M·W_j⌋`) plus its count, or [`Counts::BIG`] from 255 up (and for a count in
    /// the side list). Filled by the counting pass, which has the floor at hand, so that the
    /// writer of the runs needs no pass over the weights: see [`Counts::runs`].
    pub(crate) runs: Vec<u8>,
    /// Whether `runs` holds the current counts.
    pub(crate) runs_set: bool,
}

impl Counts {
    /// The mark of a count kept in the side list.
    pub(crate) const BIG: u8 = u8::MAX;

    pub(crate) const fn new() -> Self {
        Counts {
            small: Vec::new(),
            big: Vec::new(),
            runs: Vec::new(),
            runs_set: false,
        }
    }

    /// Ready for a round over `n` particles, which sets every count (none is cleared here).
    pub(crate) fn reset(&mut self, n: usize) {
        self.small.resize(n, 0);
        self.big.clear();
        self.runs_set = false;
    }

    /// The runs before removals (see the field), if the counting pass set them and no
    /// change to the counts since has left them stale.
    pub(crate) fn runs(&self) -> Option<&[u8]> {
        self.runs_set.then_some(&self.runs[..])
    }

    /// Set particle `j`'s count. Counts of [`Counts::BIG`] or more must be set in ascending
    /// `j`, as the rounds do. The runs go stale (the counting passes set them after
    /// their counts).
    #[inline(always)]
    pub(crate) fn set(&mut self, j: usize, c: usize) {
        self.runs_set = false;
        if c < usize::from(Self::BIG) {
            self.small[j] = c as u8;
        } else {
            debug_assert!(self.big.last().is_none_or(|&(i, _)| i < j));
            self.small[j] = Self::BIG;
            self.big.push((j, c));
        }
    }

    /// Particle `j`'s count.
    pub(crate) fn get(&self, j: usize) -> usize {
        match self.small[j] {
            Self::BIG => self.big[self.big.partition_point(|&(i, _)| i < j)].1,
            c => usize::from(c),
        }
    }

    /// Add `c` to particle `j`'s count (the rare extra draws of one particle).
    pub(crate) fn add_to(&mut self, j: usize, c: usize) {
        if self.runs_set {
            // 255 stays 255: the run is looked up either way.
            self.runs[j] = self.runs[j].saturating_add(c.min(255) as u8);
        }
        let sum = self.get(j).saturating_add(c);
        match self.small[j] {
            Self::BIG => {
                let i = self.big.partition_point(|&(i, _)| i < j);
                self.big[i].1 = sum;
            }
            _ if sum < usize::from(Self::BIG) => self.small[j] = sum as u8,
            _ => {
                let i = self.big.partition_point(|&(i, _)| i < j);
                self.small[j] = Self::BIG;
                self.big.insert(i, (j, sum));
            }
        }
    }

    /// Add another round's counts of the same particles to these (the rare rounds that top a
    /// short total up), in one pass.
    pub(crate) fn add(&mut self, other: &Counts) {
        debug_assert_eq!(self.small.len(), other.small.len());
        self.runs_set = false;
        let (mut mine, mut theirs) = (0, 0);
        let mut big = Vec::new();
        for (j, (a, &b)) in self.small.iter_mut().zip(&other.small).enumerate() {
            if *a < Self::BIG && b < Self::BIG && *a + b < Self::BIG {
                *a += b;
                continue;
            }
            let take = |c: u8, list: &[(usize, usize)], at: &mut usize| {
                if c == Self::BIG {
                    *at += 1;
                    list[*at - 1].1
                } else {
                    usize::from(c)
                }
            };
            let sum =
                take(*a, &self.big, &mut mine).saturating_add(take(b, &other.big, &mut theirs));
            *a = Self::BIG;
            big.push((j, sum));
        }
        self.big = big;
    }

    /// Every count (for tests).
    #[cfg(test)]
    pub(crate) fn to_vec(&self) -> Vec<usize> {
        (0..self.small.len()).map(|j| self.get(j)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Small and big counts set, read, added one by one and round by round, as plain
    /// `usize` counts would be.
    #[test]
    fn counts_behave_as_plain_counts() {
        let mut c = Counts::new();
        c.reset(6);
        let first = [3usize, 254, 255, 0, 1000, 7];
        for (j, &x) in first.iter().enumerate() {
            c.set(j, x);
        }
        assert_eq!(c.to_vec(), first);
        assert_eq!(c.big, [(2, 255), (4, 1000)]);
        c.add_to(1, 1);
        c.add_to(4, 5);
        c.add_to(0, 2);
        assert_eq!(c.to_vec(), [5, 255, 255, 0, 1005, 7]);
        let mut other = Counts::new();
        other.reset(6);
        for (j, &x) in [250usize, 0, 1, 300, 0, 1].iter().enumerate() {
            other.set(j, x);
        }
        c.add(&other);
        assert_eq!(c.to_vec(), [255, 255, 256, 300, 1005, 8]);
        assert!(c.big.windows(2).all(|p| p[0].0 < p[1].0));
        // A reset keeps nothing of the big counts.
        c.reset(6);
        for j in 0..6 {
            c.set(j, j);
        }
        assert_eq!(c.to_vec(), [0, 1, 2, 3, 4, 5]);
    }

    /// The runs follow the extra draws of one particle (saturating at the mark), and go
    /// stale with a set count, another round's counts or a reset.
    #[test]
    fn runs_follow_the_counts_or_go_stale() {
        let mut c = Counts::new();
        let fill = |c: &mut Counts| {
            c.reset(4);
            for j in 0..4 {
                c.set(j, j);
            }
            c.runs = vec![3, 250, 255, 0];
            c.runs_set = true;
        };
        fill(&mut c);
        c.add_to(0, 2);
        c.add_to(1, 7);
        c.add_to(2, 1);
        c.add_to(3, 1000);
        assert_eq!(c.runs(), Some(&[5u8, 255, 255, 255][..]));
        c.set(0, 1);
        assert_eq!(c.runs(), None);
        fill(&mut c);
        let mut other = Counts::new();
        other.reset(4);
        c.add(&other);
        assert_eq!(c.runs(), None);
        fill(&mut c);
        c.reset(4);
        assert_eq!(c.runs(), None);
    }
}
