//! Binding and running the server: TCP (loopback by default) or a Unix socket, optional
//! bearer token and TLS, grpc.health.v1, graceful drain; in the foreground ([`bind`] then
//! [`BoundServer::serve`]) or on a background thread ([`BackgroundServer`]).

use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use sixaxis_core::{Error, Result};
use tokio::sync::watch;
use tokio_stream::StreamExt;
use tonic::transport::{Identity, Server, ServerTlsConfig};

use crate::proto::rpc::environment_server::EnvironmentServer;
use crate::service::{EnvService, Limits, Shared};

/// Where the server listens.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Listen {
    /// A TCP address (port 0: any free port).
    Tcp(SocketAddr),
    /// A Unix domain socket path (created; removed when the server stops).
    Uds(PathBuf),
}

/// PEM certificate chain and private key of the server's TLS identity.
#[derive(Debug, Clone)]
pub struct TlsFiles {
    /// The certificate chain, PEM.
    pub cert_pem: Vec<u8>,
    /// The private key, PEM.
    pub key_pem: Vec<u8>,
}

/// Everything a server is started with.
#[derive(Debug, Clone)]
pub struct ServerConfig {
    /// Where to listen.
    pub listen: Listen,
    /// The bearer token clients must send (`authorization: Bearer TOKEN`), if any.
    pub token: Option<String>,
    /// TLS, if any.
    pub tls: Option<TlsFiles>,
    /// Limits.
    pub limits: Limits,
    /// How long a drain waits for the sessions to finish their current request.
    pub drain_timeout: Duration,
}

impl Default for ServerConfig {
    fn default() -> Self {
        ServerConfig {
            listen: Listen::Tcp(SocketAddr::from(([127, 0, 0, 1], 0))),
            token: None,
            tls: None,
            limits: Limits::default(),
            drain_timeout: Duration::from_secs(10),
        }
    }
}

impl ServerConfig {
    /// Check the configuration: a TCP address that is not loopback needs a token or TLS;
    /// an empty token and zero limits are errors naming the option.
    pub fn check(&self) -> Result<()> {
        if let Listen::Tcp(addr) = &self.listen {
            if !addr.ip().is_loopback() && self.token.is_none() && self.tls.is_none() {
                return Err(Error::argument(
                    "address",
                    addr,
                    "is not a loopback address: a server reachable from other machines needs a token (--token-file, token=) or TLS (--tls-cert/--tls-key, tls_cert=/tls_key=)",
                ));
            }
        }
        if let Some(t) = &self.token {
            if t.trim().is_empty() || t.chars().any(|c| c.is_control()) {
                return Err(Error::argument(
                    "token",
                    "(hidden)",
                    "must be non-empty printable text (no newline or control characters)",
                ));
            }
        }
        let l = &self.limits;
        for (name, v) in [
            ("max_sessions", l.max_sessions),
            ("max_worlds_per_session", l.max_worlds_per_session),
            ("max_envs_per_world", l.max_envs_per_world),
            ("max_total_envs", l.max_total_envs),
            ("max_message_bytes", l.max_message_bytes),
        ] {
            if v == 0 {
                return Err(Error::argument(name, v, "must be at least 1"));
            }
        }
        for (name, d) in [
            ("idle_timeout", l.idle_timeout),
            ("keepalive_interval", l.keepalive_interval),
            ("keepalive_timeout", l.keepalive_timeout),
        ] {
            if d.is_zero() {
                return Err(Error::argument(name, 0, "must be more than 0 seconds"));
            }
        }
        Ok(())
    }
}

/// A duration option given in seconds (`--idle-timeout`, `keepalive_interval=`, ...): a
/// finite number > 0 and below 10^9, else an error naming `name` and the value.
pub fn seconds(name: &str, value: f64) -> Result<Duration> {
    if value.is_finite() && value > 0.0 && value < 1e9 {
        Ok(Duration::from_secs_f64(value))
    } else {
        Err(Error::argument(
            name,
            value,
            "must be a number of seconds > 0",
        ))
    }
}

enum Listener {
    Tcp(tokio::net::TcpListener),
    Uds(tokio::net::UnixListener, PathBuf),
}

/// A server whose socket is bound (its address known) but that does not serve yet.
pub struct BoundServer {
    config: ServerConfig,
    listener: Listener,
    address: String,
    shared: Arc<Shared>,
    drain: watch::Sender<bool>,
}

/// What a running server holds (for monitoring and tests).
#[derive(Debug, Clone)]
pub struct Stats(Arc<Shared>);

impl Stats {
    /// Worlds alive.
    pub fn worlds(&self) -> usize {
        self.0.world_count()
    }

    /// `Process` streams open.
    pub fn sessions(&self) -> usize {
        self.0.session_count()
    }
}

impl std::fmt::Debug for BoundServer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BoundServer")
            .field("address", &self.address)
            .finish()
    }
}

/// Check `config` and bind its socket (within a tokio runtime).
pub async fn bind(config: ServerConfig) -> Result<BoundServer> {
    config.check()?;
    let (listener, address) = match &config.listen {
        Listen::Tcp(addr) => {
            let l = tokio::net::TcpListener::bind(addr)
                .await
                .map_err(|e| Error::io(addr.to_string(), e))?;
            let local = l.local_addr().map_err(|e| Error::io(addr.to_string(), e))?;
            (Listener::Tcp(l), local.to_string())
        }
        Listen::Uds(path) => {
            let l = tokio::net::UnixListener::bind(path).map_err(|e| Error::io(path, e))?;
            (
                Listener::Uds(l, path.clone()),
                format!("unix:{}", path.display()),
            )
        }
    };
    let (drain, drain_rx) = watch::channel(false);
    let shared = Arc::new(Shared::new(
        config.limits.clone(),
        config.token.as_deref(),
        drain_rx,
    ));
    Ok(BoundServer {
        config,
        listener,
        address,
        shared,
        drain,
    })
}

impl BoundServer {
    /// The bound address: `HOST:PORT` for TCP, `unix:PATH` for a Unix socket (the form
    /// gRPC clients take).
    pub fn address(&self) -> &str {
        &self.address
    }

    /// The server's counters.
    pub fn stats(&self) -> Stats {
        Stats(Arc::clone(&self.shared))
    }

    /// The bound TCP port (None for a Unix socket).
    pub fn port(&self) -> Option<u16> {
        match &self.listener {
            Listener::Tcp(l) => l.local_addr().ok().map(|a| a.port()),
            Listener::Uds(..) => None,
        }
    }

    /// Serve until `shutdown` completes, then drain: the sessions finish the request in
    /// hand and end their streams (with UNAVAILABLE), new streams are refused, and after
    /// the config's drain timeout the server stops regardless.
    pub async fn serve(self, shutdown: impl std::future::Future<Output = ()> + Send) -> Result<()> {
        let (shared, drain_tx) = (self.shared, self.drain);
        let max = self.config.limits.max_message_bytes;
        let env = EnvironmentServer::new(EnvService {
            shared: Arc::clone(&shared),
        })
        .max_decoding_message_size(max)
        .max_encoding_message_size(max);
        let (health, health_service) = tonic_health::server::health_reporter();
        health.set_serving::<EnvironmentServer<EnvService>>().await;

        let mut builder = Server::builder()
            .tcp_nodelay(true)
            .http2_keepalive_interval(Some(self.config.limits.keepalive_interval))
            .http2_keepalive_timeout(Some(self.config.limits.keepalive_timeout));
        if let Some(tls) = &self.config.tls {
            let identity = Identity::from_pem(&tls.cert_pem, &tls.key_pem);
            builder = builder
                .tls_config(ServerTlsConfig::new().identity(identity))
                .map_err(|e| {
                    Error::argument("tls", "cert/key", format!("not a usable TLS identity: {e}"))
                })?;
        }
        let router = builder.add_service(health_service).add_service(env);

        let drain_timeout = self.config.drain_timeout;
        let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
        let signal = async move {
            let _ = stop_rx.await;
        };
        let watcher = async move {
            shutdown.await;
            health
                .set_not_serving::<EnvironmentServer<EnvService>>()
                .await;
            let _ = drain_tx.send(true);
            let _ = stop_tx.send(());
        };
        let address = self.address.clone();
        let serving = async move {
            match self.listener {
                Listener::Tcp(l) => {
                    let incoming = tokio_stream::wrappers::TcpListenerStream::new(l).map(|s| {
                        s.inspect(|s| {
                            let _ = s.set_nodelay(true);
                        })
                    });
                    router.serve_with_incoming_shutdown(incoming, signal).await
                }
                Listener::Uds(l, path) => {
                    let incoming = tokio_stream::wrappers::UnixListenerStream::new(l);
                    let r = router.serve_with_incoming_shutdown(incoming, signal).await;
                    let _ = std::fs::remove_file(&path);
                    r
                }
            }
        };
        tokio::pin!(serving);
        tokio::select! {
            r = &mut serving => return r.map_err(|e| transport_error(&address, e)),
            _ = watcher => {}
        }
        match tokio::time::timeout(drain_timeout, &mut serving).await {
            Ok(r) => r.map_err(|e| transport_error(&address, e)),
            Err(_) => Ok(()),
        }
    }
}

fn transport_error(address: &str, e: tonic::transport::Error) -> Error {
    Error::io(address, std::io::Error::other(e.to_string()))
}

/// A server on its own thread with its own tokio runtime (for the Python binding, tests
/// and notebooks); stopped by [`BackgroundServer::stop`] or when dropped.
#[derive(Debug)]
pub struct BackgroundServer {
    address: String,
    port: Option<u16>,
    stats: Stats,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    thread: Option<std::thread::JoinHandle<Result<()>>>,
}

impl BackgroundServer {
    /// Start a server: returns once its socket is bound (or with the error that kept it
    /// from binding).
    pub fn start(config: ServerConfig) -> Result<BackgroundServer> {
        config.check()?;
        let (ready_tx, ready_rx) =
            std::sync::mpsc::channel::<Result<(String, Option<u16>, Stats)>>();
        let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
        let thread = std::thread::Builder::new()
            .name("sixaxis-serve".into())
            .spawn(move || -> Result<()> {
                let rt = tokio::runtime::Builder::new_multi_thread()
                    .worker_threads(2)
                    .thread_name("sixaxis-serve-worker")
                    .enable_all()
                    .build()
                    .map_err(|e| Error::io("tokio runtime", e))?;
                rt.block_on(async move {
                    let bound = match bind(config).await {
                        Ok(b) => b,
                        Err(e) => {
                            let msg = e.to_string();
                            let _ = ready_tx.send(Err(e));
                            return Err(Error::argument("server", "bind", msg));
                        }
                    };
                    let _ = ready_tx.send(Ok((
                        bound.address().to_string(),
                        bound.port(),
                        bound.stats(),
                    )));
                    bound
                        .serve(async move {
                            let _ = stop_rx.await;
                        })
                        .await
                })
            })
            .map_err(|e| Error::io("server thread", e))?;
        match ready_rx.recv() {
            Ok(Ok((address, port, stats))) => Ok(BackgroundServer {
                address,
                port,
                stats,
                stop: Some(stop_tx),
                thread: Some(thread),
            }),
            Ok(Err(e)) => {
                let _ = thread.join();
                Err(e)
            }
            Err(_) => match thread.join() {
                Ok(Err(e)) => Err(e),
                _ => Err(Error::argument(
                    "server",
                    "thread",
                    "stopped before it bound its socket",
                )),
            },
        }
    }

    /// The bound address (`HOST:PORT` or `unix:PATH`).
    pub fn address(&self) -> &str {
        &self.address
    }

    /// The bound TCP port (None for a Unix socket).
    pub fn port(&self) -> Option<u16> {
        self.port
    }

    /// The server's counters.
    pub fn stats(&self) -> &Stats {
        &self.stats
    }

    /// Whether it still serves.
    pub fn is_running(&self) -> bool {
        self.thread.as_ref().is_some_and(|t| !t.is_finished())
    }

    /// Drain and stop; waits for the server's thread. Stopping twice is a no-op.
    pub fn stop(&mut self) -> Result<()> {
        if let Some(s) = self.stop.take() {
            let _ = s.send(());
        }
        match self.thread.take().map(|t| t.join()) {
            None => Ok(()),
            Some(Ok(r)) => r,
            Some(Err(_)) => Err(Error::argument("server", "thread", "panicked")),
        }
    }
}

impl Drop for BackgroundServer {
    fn drop(&mut self) {
        let _ = self.stop();
    }
}
