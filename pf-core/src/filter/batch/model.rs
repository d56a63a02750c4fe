//! What a model gives the batch filter: arithmetic over a chunk of particles held as
//! columns.
//!
//! A state of dimension `D` lives as `D` columns of `f64`, one value per particle
//! (structure of arrays). The filter hands a model one chunk of particles at a time (a few
//! thousand, in cache) as [`Cols`]: the parents' columns, the chunk's standard normals, and
//! the columns to fill. A model written as plain loops over these slices, with no branch
//! and no call that LLVM cannot inline, is vectorised by the compiler, as the scalar
//! [`NoisyAr1`](crate::models::NoisyAr1) is.

/// A read-only chunk of `dim` columns of `len` values each, `stride` apart in one slice.
#[derive(Debug, Clone, Copy)]
pub struct Cols<'a> {
    data: &'a [f64],
    dim: usize,
    len: usize,
    stride: usize,
}

/// A writable chunk of columns (see [`Cols`]).
#[derive(Debug)]
pub struct ColsMut<'a> {
    data: &'a mut [f64],
    dim: usize,
    len: usize,
    stride: usize,
}

impl<'a> Cols<'a> {
    /// `dim` columns of `len` values laid end to end in `data` (column `k` is
    /// `data[k·len .. (k+1)·len]`); for calling a model outside the filter, as tests do.
    ///
    /// # Panics
    /// If `data.len() != dim · len`: a caller's layout error, not user data.
    pub fn new(data: &'a [f64], dim: usize, len: usize) -> Self {
        assert_eq!(
            data.len(),
            dim * len,
            "Cols::new: data is not dim × len values"
        );
        Cols::strided(data, dim, len, len)
    }

    /// Column `k` starts at `k·stride`; `data` holds at least `(dim−1)·stride + len`.
    pub(crate) fn strided(data: &'a [f64], dim: usize, len: usize, stride: usize) -> Self {
        debug_assert!(dim == 0 || data.len() >= (dim - 1) * stride + len);
        Cols {
            data,
            dim,
            len,
            stride,
        }
    }

    /// Particles in the chunk.
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the chunk holds no particle.
    #[inline(always)]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Columns (the state's or the noise's dimension).
    #[inline(always)]
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Column `k`: component `k` of every particle in the chunk.
    ///
    /// # Panics
    /// If `k ≥ dim` (a model's indexing error).
    #[inline(always)]
    pub fn col(&self, k: usize) -> &'a [f64] {
        assert!(k < self.dim, "column {k} of a {}-column chunk", self.dim);
        &self.data[k * self.stride..k * self.stride + self.len]
    }

    /// The first `K` columns as an array, `let [x, v] = cols.split::<2>();`.
    ///
    /// # Panics
    /// If `K > dim`.
    #[inline(always)]
    pub fn split<const K: usize>(&self) -> [&'a [f64]; K] {
        std::array::from_fn(|k| self.col(k))
    }

    /// Columns `from .. from + dim` as a chunk of their own (a block of the state, such as
    /// the linear part of a marginalized filter's particle).
    ///
    /// # Panics
    /// If the range passes the last column.
    #[inline(always)]
    pub fn sub(&self, from: usize, dim: usize) -> Cols<'a> {
        assert!(
            from + dim <= self.dim,
            "columns {from}..{} of {}",
            from + dim,
            self.dim
        );
        if dim == 0 {
            return Cols::strided(&[], 0, self.len, self.stride);
        }
        Cols::strided(&self.data[from * self.stride..], dim, self.len, self.stride)
    }
}

impl<'a> ColsMut<'a> {
    /// `dim` columns of `len` values laid end to end in `data` (see [`Cols::new`]).
    ///
    /// # Panics
    /// If `data.len() != dim · len`.
    pub fn new(data: &'a mut [f64], dim: usize, len: usize) -> Self {
        assert_eq!(
            data.len(),
            dim * len,
            "ColsMut::new: data is not dim × len values"
        );
        ColsMut::strided(data, dim, len, len)
    }

    pub(crate) fn strided(data: &'a mut [f64], dim: usize, len: usize, stride: usize) -> Self {
        debug_assert!(dim == 0 || data.len() >= (dim - 1) * stride + len);
        ColsMut {
            data,
            dim,
            len,
            stride,
        }
    }

    /// Particles in the chunk.
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the chunk holds no particle.
    #[inline(always)]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Columns.
    #[inline(always)]
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Column `k`, to write.
    ///
    /// # Panics
    /// If `k ≥ dim`.
    #[inline(always)]
    pub fn col_mut(&mut self, k: usize) -> &mut [f64] {
        assert!(k < self.dim, "column {k} of a {}-column chunk", self.dim);
        &mut self.data[k * self.stride..k * self.stride + self.len]
    }

    /// The first `K` columns, each writable: `let [x, v] = out.split_mut::<2>();`.
    ///
    /// # Panics
    /// If `K > dim`.
    #[inline(always)]
    pub fn split_mut<const K: usize>(&mut self) -> [&mut [f64]; K] {
        assert!(K <= self.dim, "{K} columns of a {}-column chunk", self.dim);
        let len = self.len;
        let mut cols = self.data.chunks_mut(self.stride).map(|c| &mut c[..len]);
        std::array::from_fn(|_| cols.next().expect("K ≤ dim columns"))
    }

    /// Columns `from .. from + dim`, writable (see [`Cols::sub`]).
    ///
    /// # Panics
    /// If the range passes the last column.
    #[inline(always)]
    pub fn sub_mut(&mut self, from: usize, dim: usize) -> ColsMut<'_> {
        assert!(
            from + dim <= self.dim,
            "columns {from}..{} of {}",
            from + dim,
            self.dim
        );
        if dim == 0 {
            return ColsMut::strided(&mut [], 0, self.len, self.stride);
        }
        ColsMut::strided(
            &mut self.data[from * self.stride..],
            dim,
            self.len,
            self.stride,
        )
    }

    /// The same columns, borrowed again (to pass them on and still use them after).
    #[inline(always)]
    pub fn reborrow(&mut self) -> ColsMut<'_> {
        ColsMut::strided(self.data, self.dim, self.len, self.stride)
    }

    /// The same columns, read-only.
    #[inline(always)]
    pub fn as_cols(&self) -> Cols<'_> {
        Cols::strided(self.data, self.dim, self.len, self.stride)
    }
}

/// A state-space model over chunks of particles, for [`BatchFilter`](super::BatchFilter).
///
/// `X_0 = initial(z)`, `X_t = propagate(t, u_t, X_{t−1}, z)` with `z` standard normals
/// (`noise_dim` per particle), and `log g_t(y_t | X_t)`. Every randomness of the
/// transition comes through `z`, which the filter draws per chunk from streams that make
/// the run bit-identical for any number of threads.
///
/// Write each method as loops over the columns' slices (zip them, or re-slice each to the
/// chunk's length so that indexing needs no bound check), with `#[inline]` arithmetic: no
/// branch on data where a select will do, no allocation.
pub trait BatchModel: Send + Sync {
    /// An observation `y_t` (`f64`, `[f64; 2]`, a slice type…).
    type Obs: ?Sized + Sync;
    /// The step's known input `u_t` (`()` for none).
    type Input: Sync;

    /// `D`, the state's dimension: the number of columns of a particle.
    fn dim(&self) -> usize;

    /// Standard normals each particle draws per step of [`propagate`](Self::propagate).
    fn noise_dim(&self) -> usize;

    /// Standard normals each particle draws for [`initial`](Self::initial); by default
    /// [`noise_dim`](Self::noise_dim).
    fn initial_noise_dim(&self) -> usize {
        self.noise_dim()
    }

    /// `X_0` of every particle of the chunk from its normals `z`
    /// ([`initial_noise_dim`](Self::initial_noise_dim) columns).
    fn initial(&self, z: Cols<'_>, x: ColsMut<'_>);

    /// `X_t` of every particle from its parent's state `X_{t−1}` and its normals `z`
    /// ([`noise_dim`](Self::noise_dim) columns).
    fn propagate(&self, t: usize, u: &Self::Input, parents: Cols<'_>, z: Cols<'_>, x: ColsMut<'_>);

    /// `lw[i] += log g_t(y | X_t^i)`.
    fn add_log_likelihood(&self, t: usize, y: &Self::Obs, x: Cols<'_>, lw: &mut [f64]);

    /// [`propagate`](Self::propagate), then [`add_log_likelihood`](Self::add_log_likelihood)
    /// when `y` is given. Override it to do both in one loop where that saves a pass (the
    /// scalar models do).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn propagate_weighed(
        &self,
        t: usize,
        u: &Self::Input,
        y: Option<&Self::Obs>,
        parents: Cols<'_>,
        z: Cols<'_>,
        mut x: ColsMut<'_>,
        lw: &mut [f64],
    ) {
        self.propagate(t, u, parents, z, x.reborrow());
        if let Some(y) = y {
            self.add_log_likelihood(t, y, x.as_cols(), lw);
        }
    }
}

/// The transition density of a [`BatchModel`], which a guided proposal's weights need.
pub trait BatchTransitionDensity: BatchModel {
    /// `out[i] += log f_t(X_t^i | X_{t−1}^i)` for the chunk's parents and new states.
    fn add_log_transition(
        &self,
        t: usize,
        u: &Self::Input,
        parents: Cols<'_>,
        x: Cols<'_>,
        out: &mut [f64],
    );
}

/// An importance density `q_t(x_t | x_{t−1}, y_t)` over a chunk, for
/// [`BatchFilter::guided`](super::BatchFilter::guided).
///
/// The filter weighs each new state by `g_t(y_t | x_t) f_t(x_t | x_{t−1}) / q_t(x_t |
/// x_{t−1}, y_t)` (with `y_t` missing, `f/q` alone). The initial particles come from the
/// model's own `X_0` law.
pub trait BatchProposal<M: BatchModel>: Send + Sync {
    /// Standard normals each particle draws per step.
    fn noise_dim(&self, model: &M) -> usize;

    /// Draw `X_t` for every particle of the chunk from its parent and its normals `z`, and
    /// write `log q_t(X_t | X_{t−1}, y_t)` into `log_q`.
    #[allow(clippy::too_many_arguments)]
    fn propose(
        &self,
        model: &M,
        t: usize,
        u: &M::Input,
        y: Option<&M::Obs>,
        parents: Cols<'_>,
        z: Cols<'_>,
        x: ColsMut<'_>,
        log_q: &mut [f64],
    );
}

/// A model with a scalar state, written in terms of standard normal noise: the case
/// `D = 1` of [`BatchModel`], which every `ScalarModel` is.
///
/// Implement the three methods as `#[inline]` arithmetic (no branches, no allocation) and
/// the filter's loops over them vectorise. `Send` and `Sync`, since a run's steps may go to
/// another thread of the pool (see [`BatchFilter::run`](super::BatchFilter::run)).
pub trait ScalarModel: Send + Sync {
    /// `X_0` from a standard normal `z`.
    fn initial_from_normal(&self, z: f64) -> f64;
    /// `X_t` from `x_prev` and a standard normal `z`.
    fn transition_from_normal(&self, t: usize, x_prev: f64, z: f64) -> f64;
    /// `log g_t(y | x)`.
    fn log_likelihood_scalar(&self, t: usize, x: f64, y: f64) -> f64;
}

impl<M: ScalarModel> BatchModel for M {
    type Obs = f64;
    type Input = ();

    #[inline(always)]
    fn dim(&self) -> usize {
        1
    }

    #[inline(always)]
    fn noise_dim(&self) -> usize {
        1
    }

    #[inline(always)]
    fn initial(&self, z: Cols<'_>, mut x: ColsMut<'_>) {
        for (x, &z) in x.col_mut(0).iter_mut().zip(z.col(0)) {
            *x = self.initial_from_normal(z);
        }
    }

    #[inline(always)]
    fn propagate(&self, t: usize, _u: &(), parents: Cols<'_>, z: Cols<'_>, mut x: ColsMut<'_>) {
        for ((x, &z), &xp) in x.col_mut(0).iter_mut().zip(z.col(0)).zip(parents.col(0)) {
            *x = self.transition_from_normal(t, xp, z);
        }
    }

    #[inline(always)]
    fn add_log_likelihood(&self, t: usize, &y: &f64, x: Cols<'_>, lw: &mut [f64]) {
        for (l, &x) in lw.iter_mut().zip(x.col(0)) {
            *l += self.log_likelihood_scalar(t, x, y);
        }
    }

    /// One loop that moves and weighs each particle (about 3 % at N = 10⁴ against two).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn propagate_weighed(
        &self,
        t: usize,
        _u: &(),
        y: Option<&f64>,
        parents: Cols<'_>,
        z: Cols<'_>,
        mut x: ColsMut<'_>,
        lw: &mut [f64],
    ) {
        let (xp, z) = (parents.col(0), z.col(0));
        match y {
            Some(&y) => {
                for (((x, &z), &xp), l) in x.col_mut(0).iter_mut().zip(z).zip(xp).zip(lw) {
                    *x = self.transition_from_normal(t, xp, z);
                    *l += self.log_likelihood_scalar(t, *x, y);
                }
            }
            None => self.propagate(t, &(), parents, Cols::strided(z, 1, z.len(), z.len()), x),
        }
    }
}
