//! The session: [`Client`], one bidirectional `Process` stream on a current-thread tokio
//! runtime it owns. [`Client::connect`] opens it (`timeout` / `connect_timeout` in seconds),
//! [`Client::write`] queues a request without waiting ([`Kind`] remembers what it was),
//! [`Client::read`] awaits the oldest one's answer ([`Answer`], decoded without the GIL),
//! [`Client::close`] ends the stream. A failure of the stream closes the session: every
//! later call returns the same [`ClientError`].

use std::collections::{BTreeMap, VecDeque};
use std::future::Future;
use std::pin::Pin;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use prost::Message;
use sixaxis_server::proto::environment::{Request as Req, Response as Resp};
use sixaxis_server::proto::rpc::environment_client::EnvironmentClient;
use sixaxis_server::proto::{
    ActionObservationSpecs, EnvironmentRequest, EnvironmentResponse, Tensor,
};
use tokio::runtime::Runtime;
use tokio::sync::{mpsc, Notify};
use tokio_stream::wrappers::UnboundedReceiverStream;
use tonic::metadata::MetadataValue;
use tonic::Streaming;

use super::error::ClientError;
use super::transport::{answers_in_tls, connect_once, keep, target_of, Keeper, Target};

/// The kind of a request written and not yet answered.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Kind {
    CreateWorld,
    JoinWorld,
    Step,
    Reset,
    LeaveWorld,
    DestroyWorld,
    /// An encoded request of the caller's; answered as the encoded response.
    Raw(String),
}

impl Kind {
    fn what(&self) -> &str {
        match self {
            Kind::CreateWorld => "CreateWorld",
            Kind::JoinWorld => "JoinWorld",
            Kind::Step => "Step",
            Kind::Reset => "Reset",
            Kind::LeaveWorld => "LeaveWorld",
            Kind::DestroyWorld => "DestroyWorld",
            Kind::Raw(what) => what,
        }
    }
}

/// An answer, decoded without the GIL; made Python objects by [`answer_to_py`](super::tensor::answer_to_py).
pub(super) enum Answer {
    WorldName(String),
    Specs(Option<ActionObservationSpecs>),
    Step(i32, BTreeMap<u64, Tensor>),
    Empty,
    Raw(Vec<u8>),
}

pub(super) type Opening = Pin<
    Box<
        dyn Future<Output = Result<tonic::Response<Streaming<EnvironmentResponse>>, tonic::Status>>
            + Send,
    >,
>;

/// The response side of the stream: opening (the call's headers not yet answered) or open.
pub(super) enum Inbound {
    Opening(Opening),
    Open(Box<Streaming<EnvironmentResponse>>),
    Gone,
}

/// The client proper (behind the Python object's mutex).
pub(super) struct Client {
    address: String,
    target: Target,
    timeout: Duration,
    timeout_s: f64,
    rt: Arc<Runtime>,
    tx: Option<mpsc::UnboundedSender<EnvironmentRequest>>,
    inbound: Inbound,
    pub(super) pending: VecDeque<Kind>,
    pub(super) failure: Option<ClientError>,
    keeper: Arc<Keeper>,
    keeper_thread: Option<JoinHandle<()>>,
}

impl Client {
    pub(super) fn connect(
        address: String,
        token: Option<String>,
        timeout: f64,
        connect_timeout: f64,
    ) -> Result<Client, ClientError> {
        let target = target_of(&address)?;
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_io()
            .enable_time()
            .build()
            .map_err(|e| ClientError::Ended {
                address: address.clone(),
                what: "connecting".into(),
                status: Some((2, format!("no tokio runtime: {e}"))),
            })?;
        let connect_deadline = Duration::from_secs_f64(connect_timeout);
        // As grpcio's channel_ready_future: try until the server answers or the time is up.
        let channel = rt.block_on(async {
            let t0 = Instant::now();
            let mut backoff = Duration::from_millis(20);
            loop {
                let left = connect_deadline.saturating_sub(t0.elapsed());
                if left.is_zero() {
                    return None;
                }
                if let Ok(Ok(c)) = tokio::time::timeout(left, connect_once(&target)).await {
                    return Some(c);
                }
                let left = connect_deadline.saturating_sub(t0.elapsed());
                tokio::time::sleep(backoff.min(left)).await;
                backoff = (backoff * 2).min(Duration::from_secs(1));
            }
        });
        let Some(channel) = channel else {
            return Err(ClientError::ConnectTimeout {
                address,
                timeout: connect_timeout,
            });
        };
        let (tx, rx) = mpsc::unbounded_channel();
        let tx = Some(tx);
        let mut request = tonic::Request::new(UnboundedReceiverStream::new(rx));
        if let Some(token) = &token {
            let value = MetadataValue::try_from(format!("Bearer {token}")).map_err(|_| {
                ClientError::Argument {
                    name: "token".into(),
                    value: "(hidden)".into(),
                    reason: "must be printable ASCII (it is sent as gRPC metadata)".into(),
                }
            })?;
            request.metadata_mut().insert("authorization", value);
        }
        let client = EnvironmentClient::new(channel)
            .max_decoding_message_size(usize::MAX)
            .max_encoding_message_size(usize::MAX);
        let opening: Opening = Box::pin(async move {
            let mut client = client;
            client.process(request).await
        });
        let keeper = Arc::new(Keeper {
            last_use_ms: AtomicU64::new(0),
            busy: AtomicBool::new(false),
            driving: AtomicBool::new(false),
            stop: AtomicBool::new(false),
            wake: Notify::new(),
            epoch: Instant::now(),
        });
        let rt = Arc::new(rt);
        let keeper_thread = {
            let (rt, k) = (rt.clone(), keeper.clone());
            std::thread::Builder::new()
                .name("sixaxis-client-keeper".into())
                .spawn(move || keep(&rt, &k))
                .ok()
        };
        Ok(Client {
            address,
            target,
            timeout: Duration::from_secs_f64(timeout),
            timeout_s: timeout,
            rt,
            tx,
            inbound: Inbound::Opening(opening),
            pending: VecDeque::new(),
            failure: None,
            keeper,
            keeper_thread,
        })
    }

    pub(super) fn begin(&self) {
        self.keeper.busy.store(true, Ordering::SeqCst);
        if self.keeper.driving.load(Ordering::SeqCst) {
            self.keeper.wake.notify_one();
        }
    }

    pub(super) fn end(&self) {
        self.keeper
            .last_use_ms
            .store(self.keeper.now_ms(), Ordering::SeqCst);
        self.keeper.busy.store(false, Ordering::SeqCst);
    }

    fn fail(&mut self, err: ClientError) -> ClientError {
        self.failure = Some(err.clone());
        self.pending.clear();
        self.tx = None;
        self.inbound = Inbound::Gone;
        err
    }

    /// Write one request without waiting for its answer.
    pub(super) fn write(&mut self, kind: Kind, req: Req) -> Result<(), ClientError> {
        if let Some(f) = &self.failure {
            return Err(f.clone());
        }
        let sent = self
            .tx
            .as_ref()
            .map(|tx| tx.send(EnvironmentRequest { payload: Some(req) }).is_ok())
            .unwrap_or(false);
        if !sent {
            let what = kind.what().to_string();
            return Err(self.fail(ClientError::Ended {
                address: self.address.clone(),
                what,
                status: None,
            }));
        }
        self.pending.push_back(kind);
        Ok(())
    }

    /// Let the runtime's tasks write what was queued (a few scheduler turns), so the
    /// server works on it while the caller writes to other servers.
    pub(super) fn flush(&mut self) {
        if matches!(self.inbound, Inbound::Open(_)) {
            self.rt.block_on(async {
                for _ in 0..4 {
                    tokio::task::yield_now().await;
                }
            });
        }
    }

    /// The answer to the oldest request written and not yet answered.
    pub(super) fn read(&mut self) -> Result<Answer, ClientError> {
        if let Some(f) = &self.failure {
            return Err(f.clone());
        }
        let Some(kind) = self.pending.pop_front() else {
            return Err(ClientError::Argument {
                name: "receive".into(),
                value: "()".into(),
                reason: "no request is waiting for its answer".into(),
            });
        };
        let timeout = self.timeout;
        let inbound = &mut self.inbound;
        // The timer is made inside the runtime (it needs its context).
        let mut opening = false;
        let got = self.rt.block_on(async {
            tokio::time::timeout(timeout, async {
                if let Inbound::Opening(fut) = inbound {
                    opening = true;
                    let r = fut.await;
                    *inbound = match r {
                        Ok(resp) => Inbound::Open(Box::new(resp.into_inner())),
                        Err(status) => {
                            *inbound = Inbound::Gone;
                            return Err(status);
                        }
                    };
                }
                match inbound {
                    Inbound::Open(s) => s.message().await,
                    _ => Ok(None),
                }
            })
            .await
        });
        let what = kind.what().to_string();
        let address = self.address.clone();
        let response = match got {
            Err(_) => {
                return Err(self.fail(ClientError::Timeout {
                    address,
                    what,
                    timeout: self.timeout_s,
                }))
            }
            Ok(Ok(Some(r))) => r,
            Ok(Ok(None)) => {
                return Err(self.fail(ClientError::Ended {
                    address,
                    what,
                    status: None,
                }))
            }
            Ok(Err(status)) => {
                let code = status.code() as i32;
                let details = status.message().to_string();
                // 16 UNAUTHENTICATED, 7 PERMISSION_DENIED.
                let err = if code == 16 || code == 7 {
                    ClientError::Refused {
                        address,
                        code,
                        details,
                    }
                } else if opening
                    && std::error::Error::source(&status).is_some()
                    && self.rt.block_on(answers_in_tls(&self.target))
                {
                    // The connection failed before the call's headers and the server
                    // speaks TLS to a plaintext HTTP/2 preface (docs/SERVER.md "Security").
                    ClientError::PlaintextToTls {
                        address,
                        what,
                        code,
                        details: status_chain(&status),
                    }
                } else {
                    ClientError::Ended {
                        address,
                        what,
                        status: Some((code, details)),
                    }
                };
                return Err(self.fail(err));
            }
        };
        if let Kind::Raw(_) = kind {
            return Ok(Answer::Raw(response.encode_to_vec()));
        }
        let protocol = |message: String| ClientError::Protocol {
            address: address.clone(),
            what: what.clone(),
            message,
        };
        match (kind, response.payload) {
            (_, Some(Resp::Error(s))) => Err(ClientError::Status {
                address: address.clone(),
                what: what.clone(),
                code: s.code,
                message: s.message,
            }),
            (Kind::CreateWorld, Some(Resp::CreateWorld(c))) => Ok(Answer::WorldName(c.world_name)),
            (Kind::JoinWorld, Some(Resp::JoinWorld(j))) => Ok(Answer::Specs(j.specs)),
            (Kind::Reset, Some(Resp::Reset(r))) => Ok(Answer::Specs(r.specs)),
            (Kind::Step, Some(Resp::Step(s))) => Ok(Answer::Step(s.state, s.observations)),
            (Kind::LeaveWorld, Some(Resp::LeaveWorld(_)))
            | (Kind::DestroyWorld, Some(Resp::DestroyWorld(_))) => Ok(Answer::Empty),
            (_, other) => Err(protocol(format!(
                "the answer is {} (docs/SERVER.md \"The protocol\")",
                payload_name(other.as_ref())
            ))),
        }
    }

    pub(super) fn close(&mut self) {
        if self.failure.is_none() {
            self.failure = Some(ClientError::Closed {
                address: self.address.clone(),
            });
        }
        self.pending.clear();
        self.tx = None;
        self.inbound = Inbound::Gone;
        self.keeper.stop.store(true, Ordering::SeqCst);
        self.keeper.wake.notify_one();
        if let Some(t) = self.keeper_thread.take() {
            t.thread().unpark();
            let _ = t.join();
        }
        // Drive the runtime once more so the connection task sees the stream's end and
        // tells the server (which then frees the world at once).
        self.rt.block_on(async {
            for _ in 0..4 {
                tokio::task::yield_now().await;
            }
        });
    }
}

impl Drop for Client {
    fn drop(&mut self) {
        self.keeper.stop.store(true, Ordering::SeqCst);
        self.keeper.wake.notify_one();
        if let Some(t) = self.keeper_thread.take() {
            t.thread().unpark();
            let _ = t.join();
        }
    }
}

pub(super) fn payload_name(p: Option<&Resp>) -> &'static str {
    match p {
        None => "empty",
        Some(Resp::CreateWorld(_)) => "a CreateWorld response",
        Some(Resp::JoinWorld(_)) => "a JoinWorld response",
        Some(Resp::Step(_)) => "a Step response",
        Some(Resp::Reset(_)) => "a Reset response",
        Some(Resp::ResetWorld(_)) => "a ResetWorld response",
        Some(Resp::LeaveWorld(_)) => "a LeaveWorld response",
        Some(Resp::DestroyWorld(_)) => "a DestroyWorld response",
        Some(Resp::Extension(_)) => "an extension",
        Some(Resp::Error(_)) => "an error",
    }
}

/// A Status's message and the errors under it, ": "-joined (tonic's message of a failed
/// connection is "transport error"; hyper's and h2's account of it are its sources, e.g.
/// "connection error: stream closed because of a broken pipe").
fn status_chain(status: &tonic::Status) -> String {
    let mut text = status.message().to_string();
    let mut source = std::error::Error::source(status);
    while let Some(e) = source {
        let s = e.to_string();
        if !text.contains(&s) {
            text.push_str(": ");
            text.push_str(&s);
        }
        source = e.source();
    }
    text
}
