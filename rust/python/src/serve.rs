//! `sixaxis_avoid.serve(...)`: the env server (`sixaxis-server`, docs/SERVER.md) on a
//! background thread with its own tokio runtime, as a `Server` object.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

use pyo3::prelude::*;
use sixaxis_core::Error;
use sixaxis_server::{seconds, BackgroundServer, Limits, Listen, ServerConfig, Stats, TlsFiles};

use crate::errors::run;

/// A running env server (dm_env_rpc v1 over gRPC). Made by ``serve()``; ``stop()`` (or
/// leaving its ``with`` block, or dropping it) drains and stops it.
#[pyclass(name = "Server", module = "sixaxis_avoid._core")]
pub struct PyServer {
    inner: Option<BackgroundServer>,
    address: String,
    port: Option<u16>,
    stats: Stats,
}

fn read_file(path: &std::path::Path) -> sixaxis_core::Result<Vec<u8>> {
    sixaxis_core::io::read_bounded(path, 1 << 20)
}

/// Start an env server: ``address`` ``HOST:PORT`` (port 0: any free port; anything but
/// loopback needs ``token`` or TLS) or ``uds`` a Unix socket path; ``token`` the bearer token
/// clients must send (``authorization: Bearer TOKEN``); the limits as ``sixaxis serve``'s
/// flags. Returns once the socket is bound.
#[pyfunction]
#[pyo3(signature = (
    address="127.0.0.1:0", *, uds=None, token=None, tls_cert=None, tls_key=None,
    max_sessions=None, max_worlds_per_session=None, max_envs_per_world=None,
    max_total_envs=None, max_message_bytes=None, idle_timeout=None,
    keepalive_interval=None, keepalive_timeout=None,
))]
#[allow(clippy::too_many_arguments)]
pub fn serve(
    py: Python<'_>,
    address: &str,
    uds: Option<PathBuf>,
    token: Option<String>,
    tls_cert: Option<PathBuf>,
    tls_key: Option<PathBuf>,
    max_sessions: Option<usize>,
    max_worlds_per_session: Option<usize>,
    max_envs_per_world: Option<usize>,
    max_total_envs: Option<usize>,
    max_message_bytes: Option<usize>,
    idle_timeout: Option<f64>,
    keepalive_interval: Option<f64>,
    keepalive_timeout: Option<f64>,
) -> PyResult<PyServer> {
    let address = address.to_string();
    let server = run(py, move || {
        let listen = match uds {
            Some(p) => Listen::Uds(p),
            None => Listen::Tcp(address.parse::<SocketAddr>().map_err(|_| {
                Error::argument(
                    "address",
                    &address,
                    "must be HOST:PORT with a numeric IP (\"127.0.0.1:0\", \"[::1]:50051\")",
                )
            })?),
        };
        let tls = match (tls_cert, tls_key) {
            (Some(c), Some(k)) => Some(TlsFiles {
                cert_pem: read_file(&c)?,
                key_pem: read_file(&k)?,
            }),
            (None, None) => None,
            _ => {
                return Err(Error::argument(
                    "tls_cert",
                    "one of tls_cert / tls_key",
                    "TLS needs both the certificate and the key",
                ))
            }
        };
        let d = Limits::default();
        let secs = |name: &str, v: Option<f64>, default: Duration| match v {
            None => Ok(default),
            Some(s) => seconds(name, s),
        };
        let config = ServerConfig {
            listen,
            token,
            tls,
            limits: Limits {
                max_sessions: max_sessions.unwrap_or(d.max_sessions),
                max_worlds_per_session: max_worlds_per_session.unwrap_or(d.max_worlds_per_session),
                max_envs_per_world: max_envs_per_world.unwrap_or(d.max_envs_per_world),
                max_total_envs: max_total_envs.unwrap_or(d.max_total_envs),
                max_message_bytes: max_message_bytes.unwrap_or(d.max_message_bytes),
                idle_timeout: secs("idle_timeout", idle_timeout, d.idle_timeout)?,
                keepalive_interval: secs(
                    "keepalive_interval",
                    keepalive_interval,
                    d.keepalive_interval,
                )?,
                keepalive_timeout: secs(
                    "keepalive_timeout",
                    keepalive_timeout,
                    d.keepalive_timeout,
                )?,
            },
            ..ServerConfig::default()
        };
        BackgroundServer::start(config)
    })?;
    Ok(PyServer {
        address: server.address().to_string(),
        port: server.port(),
        stats: server.stats().clone(),
        inner: Some(server),
    })
}

#[pymethods]
impl PyServer {
    /// The bound address: ``"HOST:PORT"``, or ``"unix:PATH"`` (what gRPC clients take).
    #[getter]
    fn address(&self) -> &str {
        &self.address
    }
    /// The bound TCP port (None for a Unix socket).
    #[getter]
    fn port(&self) -> Option<u16> {
        self.port
    }
    /// Whether it still serves.
    #[getter]
    fn running(&self) -> bool {
        self.inner.as_ref().is_some_and(|s| s.is_running())
    }
    /// Worlds alive.
    #[getter]
    fn worlds(&self) -> usize {
        self.stats.worlds()
    }
    /// Client streams open.
    #[getter]
    fn sessions(&self) -> usize {
        self.stats.sessions()
    }
    /// Drain (the sessions finish the request in hand) and stop; a second call does nothing.
    fn stop(&mut self, py: Python<'_>) -> PyResult<()> {
        match self.inner.take() {
            Some(mut s) => run(py, move || s.stop()),
            None => Ok(()),
        }
    }
    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }
    #[pyo3(signature = (*_args))]
    fn __exit__(
        &mut self,
        py: Python<'_>,
        _args: &Bound<'_, pyo3::types::PyTuple>,
    ) -> PyResult<bool> {
        self.stop(py)?;
        Ok(false)
    }
    fn __repr__(&self) -> String {
        let state = if self.running() { "running" } else { "stopped" };
        format!("Server(address={:?}, {state})", self.address)
    }
}
