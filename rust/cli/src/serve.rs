//! `sixaxis serve`: the env server (dm_env_rpc v1 over gRPC, docs/SERVER.md) in the
//! foreground. Prints one JSON line with the bound address on stdout once it listens, so a
//! script can ask for port 0 and read the port; SIGTERM or SIGINT drains it (the sessions
//! finish the request in hand, then the process exits 0).

use std::io::Write;
use std::net::SocketAddr;
use std::path::PathBuf;

use clap::Args;
use serde_json::json;
use sixaxis_core::{Error, Result};
use sixaxis_server::{seconds, Limits, Listen, ServerConfig, TlsFiles};

/// The flags of `sixaxis serve`.
#[derive(Args, Debug, Clone)]
pub struct ServeArgs {
    /// TCP address to listen on (port 0: any free port). Anything but loopback needs
    /// --token-file or TLS.
    #[arg(
        long,
        value_name = "HOST:PORT",
        default_value = "127.0.0.1:0",
        conflicts_with = "uds"
    )]
    address: String,
    /// Listen on this Unix domain socket instead of TCP.
    #[arg(long, value_name = "PATH")]
    uds: Option<PathBuf>,
    /// File holding the bearer token clients must send (`authorization: Bearer TOKEN`).
    #[arg(long, value_name = "FILE")]
    token_file: Option<PathBuf>,
    /// TLS certificate chain (PEM); needs --tls-key.
    #[arg(long, value_name = "FILE", requires = "tls_key")]
    tls_cert: Option<PathBuf>,
    /// TLS private key (PEM); needs --tls-cert.
    #[arg(long, value_name = "FILE", requires = "tls_cert")]
    tls_key: Option<PathBuf>,
    /// Concurrent client streams.
    #[arg(long, value_name = "N", default_value_t = Limits::default().max_sessions)]
    max_sessions: usize,
    /// Worlds one client stream may hold.
    #[arg(long, value_name = "N", default_value_t = Limits::default().max_worlds_per_session)]
    max_worlds_per_session: usize,
    /// Lanes (num_envs) of one world.
    #[arg(long, value_name = "N", default_value_t = Limits::default().max_envs_per_world)]
    max_envs_per_world: usize,
    /// Lanes of all worlds together.
    #[arg(long, value_name = "N", default_value_t = Limits::default().max_total_envs)]
    max_total_envs: usize,
    /// Largest request or response, bytes.
    #[arg(long, value_name = "BYTES", default_value_t = Limits::default().max_message_bytes)]
    max_message_bytes: usize,
    /// Close a stream (freeing its worlds) after this many seconds without a request.
    #[arg(long, value_name = "SECONDS", default_value_t = Limits::default().idle_timeout.as_secs_f64())]
    idle_timeout: f64,
    /// Send an HTTP/2 keepalive ping on a connection silent for this many seconds.
    #[arg(long, value_name = "SECONDS", default_value_t = Limits::default().keepalive_interval.as_secs_f64())]
    keepalive_interval: f64,
    /// Close a connection (freeing its worlds) whose ping is unanswered for this many seconds.
    #[arg(long, value_name = "SECONDS", default_value_t = Limits::default().keepalive_timeout.as_secs_f64())]
    keepalive_timeout: f64,
}

fn read(path: &std::path::Path) -> Result<Vec<u8>> {
    sixaxis_core::io::read_bounded(path, 1 << 20)
}

impl ServeArgs {
    /// The server configuration these flags ask for.
    pub fn config(&self) -> Result<ServerConfig> {
        let listen = match &self.uds {
            Some(p) => Listen::Uds(p.clone()),
            None => Listen::Tcp(self.address.parse::<SocketAddr>().map_err(|_| {
                Error::argument(
                    "--address",
                    &self.address,
                    "must be HOST:PORT with a numeric IP (127.0.0.1:50051, [::1]:0, 0.0.0.0:50051)",
                )
            })?),
        };
        let token = match &self.token_file {
            Some(p) => {
                let text = String::from_utf8(read(p)?).map_err(|_| {
                    Error::argument("--token-file", p.display(), "must hold UTF-8 text")
                })?;
                Some(text.trim().to_string())
            }
            None => None,
        };
        let tls = match (&self.tls_cert, &self.tls_key) {
            (Some(c), Some(k)) => Some(TlsFiles {
                cert_pem: read(c)?,
                key_pem: read(k)?,
            }),
            _ => None,
        };
        Ok(ServerConfig {
            listen,
            token,
            tls,
            limits: Limits {
                max_sessions: self.max_sessions,
                max_worlds_per_session: self.max_worlds_per_session,
                max_envs_per_world: self.max_envs_per_world,
                max_total_envs: self.max_total_envs,
                max_message_bytes: self.max_message_bytes,
                idle_timeout: seconds("--idle-timeout", self.idle_timeout)?,
                keepalive_interval: seconds("--keepalive-interval", self.keepalive_interval)?,
                keepalive_timeout: seconds("--keepalive-timeout", self.keepalive_timeout)?,
            },
            ..ServerConfig::default()
        })
    }
}

/// Run the server until SIGTERM or SIGINT.
pub fn run(args: &ServeArgs) -> Result<()> {
    let config = args.config()?;
    config.check()?;
    let rt = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .map_err(|e| Error::io("tokio runtime", e))?;
    rt.block_on(async move {
        let bound = sixaxis_server::bind(config.clone()).await?;
        let line = json!({
            "address": bound.address(),
            "port": bound.port(),
            "tls": config.tls.is_some(),
            "token": config.token.is_some(),
            "protocol": "dm_env_rpc.v1",
        });
        crate::interrupt::writing(|| {
            let mut out = std::io::stdout().lock();
            let _ = writeln!(out, "{line}");
            let _ = out.flush();
        });
        bound.serve(shutdown_signal()).await?;
        eprintln!("sixaxis serve: drained and stopped");
        Ok(())
    })
}

async fn shutdown_signal() {
    use tokio::signal::unix::{signal, SignalKind};
    let mut term = match signal(SignalKind::terminate()) {
        Ok(s) => s,
        Err(_) => {
            let _ = tokio::signal::ctrl_c().await;
            return;
        }
    };
    tokio::select! {
        _ = term.recv() => {}
        _ = tokio::signal::ctrl_c() => {}
    }
    eprintln!("sixaxis serve: draining");
}
