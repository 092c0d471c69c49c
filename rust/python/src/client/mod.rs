//! `sixaxis_avoid._core.DmEnvClient`: a dm_env_rpc v1 client of the env server in Rust
//! (tonic over the server crate's own prost messages, `sixaxis_server::proto`), the default
//! transport of `sixaxis_avoid.remote` (docs/SERVER.md "What a step costs").
//!
//! One client is one bidirectional `Process` stream. Its tokio runtime is a current-thread
//! runtime owned by the client: a request is written and its answer awaited on the calling
//! thread (no hop to another thread), with the GIL released around every round trip
//! (`errors::detached`). Requests may also be written without waiting (`send_*`) and their
//! answers read later in order (`receive`), so a vector env can have a request in flight on
//! several servers at once.
//!
//! Between calls nobody drives the runtime, so a small keeper thread drives it while the
//! client has been idle for a second: the server's HTTP/2 keepalive pings (every 30 s, 20 s
//! to answer; docs/SERVER.md "Sessions and worlds") are answered while a learner trains
//! between rollouts.
//!
//! Errors are those of the grpcio transport (python/sixaxis_avoid/remote/_session.py): a
//! `google.rpc.Status` INVALID_ARGUMENT answer is `InvalidArgumentError`, any other Status
//! `ServerError`; a refused token `PermissionError`; an overdue answer `TimeoutError`; a
//! dropped stream `ConnectionError`. A failure of the stream closes the session: every later
//! call raises the same error.
//!
//! The module's parts: the Python class here; the errors and their one mapping to Python
//! exceptions in `client/error.rs`; the connection (address, channel, keeper thread) in
//! `client/transport.rs`; the session over the stream (write, read, close) in
//! `client/session.rs`; Python values <-> tensors in `client/tensor.rs`.

mod error;
mod session;
mod tensor;
mod transport;

use std::sync::Mutex;

use numpy::PyReadonlyArrayDyn;
use prost::Message;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sixaxis_server::proto::environment::Request as Req;
use sixaxis_server::proto::{
    CreateWorldRequest, DestroyWorldRequest, EnvironmentRequest, JoinWorldRequest,
    LeaveWorldRequest, ResetRequest, Settings,
};

use crate::errors::{detached, invalid_argument};
use error::{to_py, ClientError};
use session::{Client, Kind};
use tensor::{answer_to_py, settings_of, step_request};

/// A dm_env_rpc v1 client of one env server: one ``Process`` stream (docs/SERVER.md). Made
/// by ``sixaxis_avoid.remote`` (its default transport); ``address`` is ``"host:port"`` or
/// ``"unix:PATH"``, ``token`` the server's bearer token, ``timeout`` the seconds an answer
/// may take and ``connect_timeout`` the connection's. Requests are written with the
/// ``send_*`` methods and answered in order by :meth:`receive`; :meth:`step` is a Step's
/// round trip. The GIL is released while the client waits.
#[pyclass(name = "DmEnvClient", module = "sixaxis_avoid._core")]
pub struct PyDmEnvClient {
    inner: Mutex<Client>,
    address: String,
}

impl PyDmEnvClient {
    /// Run `f` on the client with the GIL released (the binding's one helper).
    fn with<T: Send>(
        &self,
        py: Python<'_>,
        f: impl Send + FnOnce(&mut Client) -> Result<T, ClientError>,
    ) -> PyResult<T> {
        let inner = &self.inner;
        detached(
            py,
            move || {
                let mut c = inner.lock().unwrap_or_else(|e| e.into_inner());
                c.begin();
                let r = f(&mut c);
                c.end();
                r
            },
            to_py,
        )
    }

    fn send(&self, py: Python<'_>, kind: Kind, req: Req) -> PyResult<()> {
        self.with(py, move |c| {
            c.write(kind, req)?;
            c.flush();
            Ok(())
        })
    }
}

#[pymethods]
impl PyDmEnvClient {
    #[new]
    #[pyo3(signature = (address, *, token=None, timeout=30.0, connect_timeout=10.0))]
    fn new(
        py: Python<'_>,
        address: String,
        token: Option<String>,
        timeout: f64,
        connect_timeout: f64,
    ) -> PyResult<Self> {
        for (name, v) in [("timeout", timeout), ("connect_timeout", connect_timeout)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(invalid_argument(
                    py,
                    name,
                    v,
                    "must be a positive number of seconds",
                ));
            }
        }
        let a = address.clone();
        let client = detached(
            py,
            move || Client::connect(a, token, timeout, connect_timeout),
            to_py,
        )?;
        Ok(PyDmEnvClient {
            inner: Mutex::new(client),
            address,
        })
    }

    /// The server's address as given.
    #[getter]
    fn address(&self) -> String {
        self.address.clone()
    }

    /// Requests written and not yet answered.
    #[getter]
    fn pending(&self) -> usize {
        self.inner.lock().map(|c| c.pending.len()).unwrap_or(0)
    }

    /// Whether the stream failed or was closed (every later call raises).
    #[getter]
    fn failed(&self) -> bool {
        self.inner
            .lock()
            .map(|c| c.failure.is_some())
            .unwrap_or(true)
    }

    /// Write a CreateWorld request; its answer is the world's name.
    #[pyo3(signature = (settings=None))]
    fn send_create_world(
        &self,
        py: Python<'_>,
        settings: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<()> {
        let settings = settings_of(settings).map_err(|e| to_py(py, e))?;
        self.send(
            py,
            Kind::CreateWorld,
            Req::CreateWorld(CreateWorldRequest { settings }),
        )
    }

    /// Write a JoinWorld request; its answer is the specs, ``{"actions": {uid: (name,
    /// dtype, shape)}, "observations": {...}}`` (``dtype`` the protocol's DataType number).
    fn send_join_world(&self, py: Python<'_>, world_name: String) -> PyResult<()> {
        self.send(
            py,
            Kind::JoinWorld,
            Req::JoinWorld(JoinWorldRequest {
                world_name,
                settings: Settings::new(),
            }),
        )
    }

    /// Write a Reset request (``settings``: ``seed``); its answer is the specs.
    #[pyo3(signature = (settings=None))]
    fn send_reset(&self, py: Python<'_>, settings: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
        let settings = settings_of(settings).map_err(|e| to_py(py, e))?;
        self.send(py, Kind::Reset, Req::Reset(ResetRequest { settings }))
    }

    /// Write a Step request: ``actions`` (int32, shaped as the action spec; None: none) for
    /// the action ``action_uid``, asking for the observations ``requested``. Its answer is
    /// ``(state, {uid: flat array})``.
    #[pyo3(signature = (actions, requested, action_uid=1))]
    fn send_step(
        &self,
        py: Python<'_>,
        actions: Option<PyReadonlyArrayDyn<'_, i32>>,
        requested: Vec<u64>,
        action_uid: u64,
    ) -> PyResult<()> {
        let req = step_request(actions, requested, action_uid);
        self.send(py, Kind::Step, req)
    }

    /// Write a LeaveWorld request; its answer is None.
    fn send_leave_world(&self, py: Python<'_>) -> PyResult<()> {
        self.send(py, Kind::LeaveWorld, Req::LeaveWorld(LeaveWorldRequest {}))
    }

    /// Write a DestroyWorld request; its answer is None.
    fn send_destroy_world(&self, py: Python<'_>, world_name: String) -> PyResult<()> {
        self.send(
            py,
            Kind::DestroyWorld,
            Req::DestroyWorld(DestroyWorldRequest { world_name }),
        )
    }

    /// Write an encoded ``EnvironmentRequest`` (``what`` names it in errors); its answer is
    /// the encoded ``EnvironmentResponse`` (an error Status inside it is not raised).
    fn send_raw(&self, py: Python<'_>, request: &[u8], what: String) -> PyResult<()> {
        let req = EnvironmentRequest::decode(request)
            .ok()
            .and_then(|r| r.payload)
            .ok_or_else(|| {
                invalid_argument(
                    py,
                    "request",
                    format!("{} bytes", request.len()),
                    "must be an encoded dm_env_rpc EnvironmentRequest with a payload",
                )
            })?;
        self.send(py, Kind::Raw(what), req)
    }

    /// The answer to the oldest request written and not yet answered (waits at most
    /// ``timeout`` seconds).
    fn receive<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let a = self.with(py, |c| c.read())?;
        answer_to_py(py, a)
    }

    /// A Step's round trip (``send_step`` then ``receive`` with one release of the GIL);
    /// only when no request is waiting for its answer.
    #[pyo3(signature = (actions, requested, action_uid=1))]
    fn step<'py>(
        &self,
        py: Python<'py>,
        actions: Option<PyReadonlyArrayDyn<'py, i32>>,
        requested: Vec<u64>,
        action_uid: u64,
    ) -> PyResult<Bound<'py, PyAny>> {
        let req = step_request(actions, requested, action_uid);
        let a = self.with(py, move |c| {
            if !c.pending.is_empty() {
                return Err(ClientError::Argument {
                    name: "step".into(),
                    value: format!("{} pending", c.pending.len()),
                    reason: "receive the answers of the requests written before".into(),
                });
            }
            c.write(Kind::Step, req)?;
            c.read()
        })?;
        answer_to_py(py, a)
    }

    /// End the stream (no LeaveWorld / DestroyWorld: the server frees the session's worlds
    /// when its stream ends); every later call raises ``ConnectionError``.
    fn close(&self, py: Python<'_>) -> PyResult<()> {
        self.with(py, |c| {
            c.close();
            Ok(())
        })
    }

    fn __repr__(&self) -> String {
        format!("DmEnvClient({:?})", self.address)
    }
}
