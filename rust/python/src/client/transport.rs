//! The connection: where to connect ([`Target`]: TCP `host:port` or a Unix socket), one
//! attempt to open the channel ([`connect_once`]), and the keeper thread ([`Keeper`],
//! [`keep`]) that drives the idle client's runtime so the server's HTTP/2 keepalive pings
//! are answered (docs/SERVER.md "Sessions and worlds"). Durations in ms or s as named.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use tokio::runtime::Runtime;
use tokio::sync::Notify;
use tonic::transport::{Channel, Endpoint};

use super::error::ClientError;

/// Where to connect: TCP `host:port` or a Unix socket (`unix:PATH`, `unix://PATH`).
pub(super) enum Target {
    Tcp(String),
    Uds(PathBuf),
}

pub(super) fn target_of(address: &str) -> Result<Target, ClientError> {
    let bad = |reason: &str| ClientError::Argument {
        name: "address".into(),
        value: format!("{address:?}"),
        reason: reason.into(),
    };
    if let Some(path) = address.strip_prefix("unix:") {
        let path = path.strip_prefix("//").unwrap_or(path);
        if path.is_empty() {
            return Err(bad("names no socket path (\"unix:/tmp/sixaxis.sock\")"));
        }
        return Ok(Target::Uds(PathBuf::from(path)));
    }
    if address.contains("://") || !address.contains(':') {
        return Err(bad(
            "must be \"host:port\" or \"unix:PATH\" (TLS: the grpc transport with credentials)",
        ));
    }
    Ok(Target::Tcp(address.to_string()))
}

pub(super) async fn connect_once(target: &Target) -> Result<Channel, String> {
    match target {
        Target::Tcp(a) => {
            let ep = Endpoint::from_shared(format!("http://{a}"))
                .map_err(|e| e.to_string())?
                .tcp_nodelay(true);
            ep.connect().await.map_err(|e| e.to_string())
        }
        Target::Uds(path) => {
            // The authority h2 accepts (docs/SERVER.md "Connecting with dm_env_rpc's Python
            // client": a socket path is not one).
            let ep = Endpoint::from_static("http://localhost");
            let path = path.clone();
            ep.connect_with_connector(tower::service_fn(move |_: tonic::transport::Uri| {
                let path = path.clone();
                async move {
                    let s = tokio::net::UnixStream::connect(path).await?;
                    Ok::<_, std::io::Error>(hyper_util::rt::TokioIo::new(s))
                }
            }))
            .await
            .map_err(|e| e.to_string())
        }
    }
}

/// Whether the server at `target` answers the HTTP/2 client preface with a TLS record (a
/// server started with `--tls-cert`/`--tls-key` sends an alert: content type 21, version
/// 3.x): one short-lived connection, false if nothing answers within half a second. Asked
/// only after a connection failed before the call's headers, to tell the caller why.
pub(super) async fn answers_in_tls(target: &Target) -> bool {
    use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};
    async fn first_bytes<S: AsyncRead + AsyncWrite + Unpin>(mut s: S) -> std::io::Result<[u8; 2]> {
        s.write_all(b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n").await?;
        let mut head = [0u8; 2];
        s.read_exact(&mut head).await?;
        Ok(head)
    }
    let probe = async {
        match target {
            Target::Tcp(a) => first_bytes(tokio::net::TcpStream::connect(a).await?).await,
            Target::Uds(p) => first_bytes(tokio::net::UnixStream::connect(p).await?).await,
        }
    };
    // TLS record types 20-23 (change_cipher_spec, alert, handshake, application_data),
    // then the major version 3; an HTTP/2 server's first frame (SETTINGS) begins 0x00.
    matches!(
        tokio::time::timeout(Duration::from_millis(500), probe).await,
        Ok(Ok([20..=23, 3]))
    )
}

/// What the keeper thread and the calls share.
pub(super) struct Keeper {
    /// Milliseconds since `epoch` at the end of the last call.
    pub(super) last_use_ms: AtomicU64,
    pub(super) busy: AtomicBool,
    pub(super) driving: AtomicBool,
    pub(super) stop: AtomicBool,
    pub(super) wake: Notify,
    pub(super) epoch: Instant,
}

impl Keeper {
    pub(super) fn now_ms(&self) -> u64 {
        self.epoch.elapsed().as_millis() as u64
    }
}

/// The keeper thread: drives the runtime while the client has been idle a second, so the
/// connection answers HTTP/2 pings; hands it back as soon as a call begins.
pub(super) fn keep(rt: &Runtime, k: &Keeper) {
    const IDLE_MS: u64 = 1000;
    while !k.stop.load(Ordering::SeqCst) {
        std::thread::park_timeout(Duration::from_millis(500));
        if k.stop.load(Ordering::SeqCst) {
            break;
        }
        let idle = k
            .now_ms()
            .saturating_sub(k.last_use_ms.load(Ordering::SeqCst))
            >= IDLE_MS;
        if idle && !k.busy.load(Ordering::SeqCst) {
            k.driving.store(true, Ordering::SeqCst);
            if !k.busy.load(Ordering::SeqCst) {
                rt.block_on(async {
                    let _ = tokio::time::timeout(Duration::from_secs(1), k.wake.notified()).await;
                });
            }
            k.driving.store(false, Ordering::SeqCst);
        }
    }
}
