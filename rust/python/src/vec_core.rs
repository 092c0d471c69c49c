//! The glue both native vector engines share (`VecEnvCore` over the grid's `BatchEnv`,
//! `JointVecEnvCore` over the joint env's `JointBatch`): the NumPy arrays an engine owns
//! and lends to the core's [`Batch`] as its buffers, the reset mask, the actions as a slice,
//! the GIL released around each call, and the `#[pymethods]` they have in common
//! ([`vec_pymethods!`]).

use numpy::{
    ndarray::Dimension, Element, PyArray1, PyArrayMethods, PyReadonlyArray, PyReadonlyArray1,
    PyReadwriteArray1,
};
use pyo3::prelude::*;
use sixaxis_core::batch::{Batch, Lane, StepRows};

use crate::errors::run;

/// The rows every batch writes ([`StepRows`]), as NumPy arrays of `n` entries an engine
/// owns (overwritten by every call; Python reads them through the engine's getters).
pub(crate) struct StepArrays {
    pub(crate) rewards: Py<PyArray1<f64>>,
    pub(crate) terminated: Py<PyArray1<bool>>,
    pub(crate) truncated: Py<PyArray1<bool>>,
    pub(crate) detour: Py<PyArray1<f64>>,
}

/// [`StepArrays`] borrowed read-write for one call.
pub(crate) struct StepLease<'py> {
    rewards: PyReadwriteArray1<'py, f64>,
    terminated: PyReadwriteArray1<'py, bool>,
    truncated: PyReadwriteArray1<'py, bool>,
    detour: PyReadwriteArray1<'py, f64>,
}

impl StepArrays {
    /// Zeroed arrays of `n` entries.
    pub(crate) fn new(py: Python<'_>, n: usize) -> StepArrays {
        StepArrays {
            rewards: PyArray1::zeros(py, n, false).unbind(),
            terminated: PyArray1::from_vec(py, vec![false; n]).unbind(),
            truncated: PyArray1::from_vec(py, vec![false; n]).unbind(),
            detour: PyArray1::zeros(py, n, false).unbind(),
        }
    }

    /// Borrow the arrays read-write (an error if Python holds a borrow of one).
    pub(crate) fn lease<'py>(&self, py: Python<'py>) -> PyResult<StepLease<'py>> {
        Ok(StepLease {
            rewards: self.rewards.bind(py).try_readwrite()?,
            terminated: self.terminated.bind(py).try_readwrite()?,
            truncated: self.truncated.bind(py).try_readwrite()?,
            detour: self.detour.bind(py).try_readwrite()?,
        })
    }
}

impl StepLease<'_> {
    /// The borrowed arrays as the core's rows.
    pub(crate) fn rows(&mut self) -> PyResult<StepRows<'_>> {
        Ok(StepRows {
            rewards: self.rewards.as_slice_mut()?,
            terminated: self.terminated.as_slice_mut()?,
            truncated: self.truncated.as_slice_mut()?,
            detour_penalty: self.detour.as_slice_mut()?,
        })
    }
}

/// The NumPy arrays of a vector engine, lent to its batch as the core's buffers.
pub(crate) trait NumpyBuffers {
    /// The batch's lane type.
    type Lane: Lane;
    /// The rows every batch writes.
    fn step_arrays(&self) -> &StepArrays;
    /// Borrow every array read-write and call `f` with them as the core's buffers.
    fn lend<F>(&self, py: Python<'_>, f: F) -> PyResult<()>
    where
        F: for<'b> FnOnce(<Self::Lane as Lane>::Buffers<'b>) -> PyResult<()>;
}

/// `f(batch, buffers)` with the GIL released (the engine's arrays lent as `buffers`).
pub(crate) fn call<A, F>(
    py: Python<'_>,
    batch: &mut Batch<A::Lane>,
    arrays: &A,
    f: F,
) -> PyResult<()>
where
    A: NumpyBuffers,
    Batch<A::Lane>: Send,
    for<'b> <A::Lane as Lane>::Buffers<'b>: Send,
    F: Send
        + for<'b> FnOnce(
            &mut Batch<A::Lane>,
            <A::Lane as Lane>::Buffers<'b>,
        ) -> sixaxis_core::Result<()>,
{
    arrays.lend(py, |bufs| run(py, || f(batch, bufs)))
}

/// `Batch::reset` of the lanes where `mask` is true (all if None), into the engine's arrays.
pub(crate) fn reset<A>(
    py: Python<'_>,
    batch: &mut Batch<A::Lane>,
    arrays: &A,
    mask: Option<PyReadonlyArray1<'_, bool>>,
) -> PyResult<()>
where
    A: NumpyBuffers,
    Batch<A::Lane>: Send,
    for<'b> <A::Lane as Lane>::Buffers<'b>: Send,
{
    let mask: Option<Vec<bool>> = mask.map(|m| m.as_array().to_vec());
    call(py, batch, arrays, |b, bufs| b.reset(mask.as_deref(), bufs))
}

/// The values of `arr` as one row-major slice: its own when contiguous, else copied into
/// `owned`.
pub(crate) fn row_major<'a, T, D>(
    arr: &'a PyReadonlyArray<'_, T, D>,
    owned: &'a mut Vec<T>,
) -> &'a [T]
where
    T: Element + Copy,
    D: Dimension,
{
    match arr.as_slice() {
        Ok(s) => s,
        Err(_) => {
            *owned = arr.as_array().iter().copied().collect();
            owned
        }
    }
}

/// The `#[pymethods]` every vector engine has (over its fields `batch`, the core's
/// [`Batch`], and `arrays`, its [`NumpyBuffers`]), added to the engine's own (`extra`) and
/// handed to `$emit!($($args)*, { items })`, the macro that writes the block.
macro_rules! vec_pymethods {
    ($emit:ident!($($args:tt)*), { $($extra:tt)* }) => {
        $emit!($($args)*, {
            $($extra)*

            /// Reset the envs where ``mask`` is true (all if None), writing into the buffers.
            #[pyo3(signature = (mask=None))]
            fn reset(
                &mut self,
                py: Python<'_>,
                mask: Option<numpy::PyReadonlyArray1<'_, bool>>,
            ) -> PyResult<()> {
                crate::vec_core::reset(py, &mut self.batch, &self.arrays, mask)
            }
            #[getter]
            fn num_envs(&self) -> usize {
                self.batch.len()
            }
            #[getter]
            fn rewards(&self, py: Python<'_>) -> Py<numpy::PyArray1<f64>> {
                crate::vec_core::NumpyBuffers::step_arrays(&self.arrays).rewards.clone_ref(py)
            }
            #[getter]
            fn terminated(&self, py: Python<'_>) -> Py<numpy::PyArray1<bool>> {
                crate::vec_core::NumpyBuffers::step_arrays(&self.arrays).terminated.clone_ref(py)
            }
            #[getter]
            fn truncated(&self, py: Python<'_>) -> Py<numpy::PyArray1<bool>> {
                crate::vec_core::NumpyBuffers::step_arrays(&self.arrays).truncated.clone_ref(py)
            }
            /// Eq. 9's part of each env's last reward, before ``reward_scale`` (0 after a reset).
            #[getter]
            fn detour_penalty(&self, py: Python<'_>) -> Py<numpy::PyArray1<f64>> {
                crate::vec_core::NumpyBuffers::step_arrays(&self.arrays).detour.clone_ref(py)
            }
            /// Steps since the reset, per env.
            #[getter]
            fn steps<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<u32>> {
                numpy::PyArray1::from_iter(
                    py,
                    self.batch.episodes().iter().map(sixaxis_core::batch::Lane::steps),
                )
            }
        });
    };
}
pub(crate) use vec_pymethods;

/// `#[$attr] impl $t { items }`: what [`vec_pymethods!`] hands its items to for an engine
/// with no other shared methods.
macro_rules! impl_block {
    (#[$attr:meta] $t:ty, { $($items:tt)* }) => {
        #[$attr]
        impl $t {
            $($items)*
        }
    };
}
pub(crate) use impl_block;
