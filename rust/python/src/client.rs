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

use std::collections::{BTreeMap, VecDeque};
use std::future::Future;
use std::path::PathBuf;
use std::pin::Pin;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use numpy::{IntoPyArray, PyArrayDescrMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use prost::Message;
use pyo3::exceptions::{PyConnectionError, PyPermissionError, PyTimeoutError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyDict, PyList, PyString};
use sixaxis_server::proto::environment::{Request as Req, Response as Resp};
use sixaxis_server::proto::rpc::environment_client::EnvironmentClient;
use sixaxis_server::proto::tensor::{
    BoolArray, DoubleArray, FloatArray, Int64Array, Payload, StringArray, Uint64Array,
};
use sixaxis_server::proto::{
    ActionObservationSpecs, CreateWorldRequest, DestroyWorldRequest, EnvironmentRequest,
    EnvironmentResponse, JoinWorldRequest, LeaveWorldRequest, ResetRequest, Settings, StepRequest,
    Tensor, TensorSpec,
};
use tokio::runtime::Runtime;
use tokio::sync::{mpsc, Notify};
use tokio_stream::wrappers::UnboundedReceiverStream;
use tonic::metadata::MetadataValue;
use tonic::transport::{Channel, Endpoint};
use tonic::Streaming;

use crate::convert::repr;
use crate::errors::{detached, invalid_argument, invalid_argument_message};

/// The gRPC status code names (as grpcio's `StatusCode` names them).
fn code_name(code: i32) -> String {
    const NAMES: [&str; 17] = [
        "OK",
        "CANCELLED",
        "UNKNOWN",
        "INVALID_ARGUMENT",
        "DEADLINE_EXCEEDED",
        "NOT_FOUND",
        "ALREADY_EXISTS",
        "PERMISSION_DENIED",
        "RESOURCE_EXHAUSTED",
        "FAILED_PRECONDITION",
        "ABORTED",
        "OUT_OF_RANGE",
        "UNIMPLEMENTED",
        "INTERNAL",
        "UNAVAILABLE",
        "DATA_LOSS",
        "UNAUTHENTICATED",
    ];
    usize::try_from(code)
        .ok()
        .and_then(|c| NAMES.get(c))
        .map_or_else(|| format!("code {code}"), |n| (*n).to_string())
}

/// Seconds as Python prints a float (`0.3`, `30.0`), so the messages read as the grpcio
/// transport's.
fn seconds(s: f64) -> String {
    if s.is_finite() && s.fract() == 0.0 {
        format!("{s:.1}")
    } else {
        format!("{s}")
    }
}

/// What went wrong, mapped to a Python exception by [`to_py`].
#[derive(Clone, Debug)]
enum ClientError {
    /// No server answered the connection in time.
    ConnectTimeout { address: String, timeout: f64 },
    /// An answer was overdue; the session is closed.
    Timeout {
        address: String,
        what: String,
        timeout: f64,
    },
    /// The server refused the session (UNAUTHENTICATED, PERMISSION_DENIED).
    Refused {
        address: String,
        code: i32,
        details: String,
    },
    /// The stream ended (`status`: its code and details, if it ended with one).
    Ended {
        address: String,
        what: String,
        status: Option<(i32, String)>,
    },
    /// `close()` was called.
    Closed { address: String },
    /// The server answered a request with an error Status; the stream goes on.
    Status {
        address: String,
        what: String,
        code: i32,
        message: String,
    },
    /// An answer that breaks the protocol (a wrong payload).
    Protocol {
        address: String,
        what: String,
        message: String,
    },
    /// A bad argument of a method (`InvalidArgumentError`).
    Argument {
        name: String,
        value: String,
        reason: String,
    },
}

/// The one mapping of a client error to its Python exception (the classes of the grpcio
/// transport, python/sixaxis_avoid/remote/_session.py).
fn to_py(py: Python<'_>, err: ClientError) -> PyErr {
    match err {
        ClientError::ConnectTimeout { address, timeout } => PyTimeoutError::new_err(format!(
            "no env server answered at {address} within connect_timeout={} s",
            seconds(timeout)
        )),
        ClientError::Timeout {
            address,
            what,
            timeout,
        } => PyTimeoutError::new_err(format!(
            "the env server at {address} did not answer {what} within timeout={} s; the \
             session is closed: make a new env",
            seconds(timeout)
        )),
        ClientError::Refused {
            address,
            code,
            details,
        } => PyPermissionError::new_err(format!(
            "the env server at {address} refused the session ({}: {details}); pass the \
             server's token=...",
            code_name(code)
        )),
        ClientError::Ended {
            address,
            what,
            status: None,
        } => PyConnectionError::new_err(format!(
            "the env server at {address} ended the session during {what}; the world is gone: \
             make a new env"
        )),
        ClientError::Ended {
            address,
            what,
            status: Some((code, details)),
        } => PyConnectionError::new_err(format!(
            "the env server at {address} ended the session during {what} ({}: {details}); \
             the world is gone: make a new env",
            code_name(code)
        )),
        ClientError::Closed { address } => {
            PyConnectionError::new_err(format!("the session with {address} is closed"))
        }
        // The server checks with the core's table, in the in-process env's words.
        ClientError::Status {
            code: 3, message, ..
        } => invalid_argument_message(py, message),
        ClientError::Status {
            address,
            what,
            code,
            message,
        } => server_error(py, &address, &what, Some(code), &message),
        ClientError::Protocol {
            address,
            what,
            message,
        } => server_error(py, &address, &what, None, &message),
        ClientError::Argument {
            name,
            value,
            reason,
        } => invalid_argument(py, &name, value, reason),
    }
}

/// `sixaxis_avoid.remote.ServerError(address, what, code, message)`.
fn server_error(
    py: Python<'_>,
    address: &str,
    what: &str,
    code: Option<i32>,
    message: &str,
) -> PyErr {
    let made = py
        .import("sixaxis_avoid.remote._session")
        .and_then(|m| m.getattr("ServerError"))
        .and_then(|cls| cls.call1((address, what, code, message)));
    match made {
        Ok(e) => PyErr::from_value(e),
        Err(e) => e,
    }
}

/// The kind of a request written and not yet answered.
#[derive(Clone, Debug, PartialEq)]
enum Kind {
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

/// An answer, decoded without the GIL; made Python objects by [`answer_to_py`].
enum Answer {
    WorldName(String),
    Specs(Option<ActionObservationSpecs>),
    Step(i32, BTreeMap<u64, Tensor>),
    Empty,
    Raw(Vec<u8>),
}

type Opening = Pin<
    Box<
        dyn Future<Output = Result<tonic::Response<Streaming<EnvironmentResponse>>, tonic::Status>>
            + Send,
    >,
>;

/// The response side of the stream: opening (the call's headers not yet answered) or open.
enum Inbound {
    Opening(Opening),
    Open(Box<Streaming<EnvironmentResponse>>),
    Gone,
}

/// What the keeper thread and the calls share.
struct Keeper {
    /// Milliseconds since `epoch` at the end of the last call.
    last_use_ms: AtomicU64,
    busy: AtomicBool,
    driving: AtomicBool,
    stop: AtomicBool,
    wake: Notify,
    epoch: Instant,
}

impl Keeper {
    fn now_ms(&self) -> u64 {
        self.epoch.elapsed().as_millis() as u64
    }
}

/// The client proper (behind the Python object's mutex).
struct Client {
    address: String,
    timeout: Duration,
    timeout_s: f64,
    rt: Arc<Runtime>,
    tx: Option<mpsc::UnboundedSender<EnvironmentRequest>>,
    inbound: Inbound,
    pending: VecDeque<Kind>,
    failure: Option<ClientError>,
    keeper: Arc<Keeper>,
    keeper_thread: Option<JoinHandle<()>>,
}

/// Where to connect: TCP `host:port` or a Unix socket (`unix:PATH`, `unix://PATH`).
enum Target {
    Tcp(String),
    Uds(PathBuf),
}

fn target_of(address: &str) -> Result<Target, ClientError> {
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

async fn connect_once(target: &Target) -> Result<Channel, String> {
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

impl Client {
    fn connect(
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

    fn begin(&self) {
        self.keeper.busy.store(true, Ordering::SeqCst);
        if self.keeper.driving.load(Ordering::SeqCst) {
            self.keeper.wake.notify_one();
        }
    }

    fn end(&self) {
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
    fn write(&mut self, kind: Kind, req: Req) -> Result<(), ClientError> {
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
    fn flush(&mut self) {
        if matches!(self.inbound, Inbound::Open(_)) {
            self.rt.block_on(async {
                for _ in 0..4 {
                    tokio::task::yield_now().await;
                }
            });
        }
    }

    /// The answer to the oldest request written and not yet answered.
    fn read(&mut self) -> Result<Answer, ClientError> {
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
        let got = self.rt.block_on(async move {
            tokio::time::timeout(timeout, async {
                if let Inbound::Opening(fut) = inbound {
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

    fn close(&mut self) {
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

fn payload_name(p: Option<&Resp>) -> &'static str {
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

/// The keeper thread: drives the runtime while the client has been idle a second, so the
/// connection answers HTTP/2 pings; hands it back as soon as a call begins.
fn keep(rt: &Runtime, k: &Keeper) {
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

// Python values <-> tensors ---------------------------------------------------------------------

fn bad_setting(name: &str, value: &Bound<'_, PyAny>) -> ClientError {
    ClientError::Argument {
        name: format!("settings[{name:?}]"),
        value: repr(value),
        reason: "must be a str, a bool, a number or a numeric array".into(),
    }
}

/// A setting's tensor: a str, a bool, a number or a NumPy array (bool, integer, float).
fn tensor_of(name: &str, value: &Bound<'_, PyAny>) -> Result<Tensor, ClientError> {
    let py = value.py();
    if let Ok(s) = value.cast::<PyString>() {
        let s = s.to_cow().map_err(|_| bad_setting(name, value))?;
        return Ok(Tensor {
            payload: Some(Payload::Strings(StringArray {
                array: vec![s.into_owned()],
            })),
            shape: vec![],
        });
    }
    if let Ok(b) = value.cast::<PyBool>() {
        return Ok(Tensor {
            payload: Some(Payload::Bools(BoolArray {
                array: vec![b.is_true()],
            })),
            shape: vec![],
        });
    }
    let arr = py
        .import("numpy")
        .and_then(|np| np.call_method1("asarray", (value,)))
        .map_err(|_| bad_setting(name, value))?;
    let arr = arr
        .cast::<numpy::PyUntypedArray>()
        .map_err(|_| bad_setting(name, value))?;
    let shape: Vec<i32> = arr.shape().iter().map(|&d| d as i32).collect();
    let kind = arr.dtype().kind();
    let as_type = |t: &str| -> Result<Bound<'_, PyAny>, ClientError> {
        arr.call_method1("astype", (t,))
            .map_err(|_| bad_setting(name, value))
    };
    fn flat<T: numpy::Element + Copy>(a: &Bound<'_, PyAny>) -> Option<Vec<T>> {
        let a: PyReadonlyArrayDyn<'_, T> = a.extract().ok()?;
        Some(a.as_array().iter().copied().collect())
    }
    let payload = match kind {
        b'b' => Payload::Bools(BoolArray {
            array: flat(arr.as_any()).ok_or_else(|| bad_setting(name, value))?,
        }),
        b'i' => Payload::Int64s(Int64Array {
            array: flat(&as_type("int64")?).ok_or_else(|| bad_setting(name, value))?,
        }),
        b'u' => Payload::Uint64s(Uint64Array {
            array: flat(&as_type("uint64")?).ok_or_else(|| bad_setting(name, value))?,
        }),
        b'f' if arr.dtype().itemsize() == 4 => Payload::Floats(FloatArray {
            array: flat(arr.as_any()).ok_or_else(|| bad_setting(name, value))?,
        }),
        b'f' => Payload::Doubles(DoubleArray {
            array: flat(&as_type("float64")?).ok_or_else(|| bad_setting(name, value))?,
        }),
        _ => return Err(bad_setting(name, value)),
    };
    Ok(Tensor {
        payload: Some(payload),
        shape,
    })
}

fn settings_of(settings: Option<&Bound<'_, PyDict>>) -> Result<Settings, ClientError> {
    let mut out = Settings::new();
    if let Some(d) = settings {
        for (k, v) in d.iter() {
            let name: String = k.extract().map_err(|_| ClientError::Argument {
                name: "settings".into(),
                value: repr(&k),
                reason: "its keys must be str".into(),
            })?;
            let t = tensor_of(&name, &v)?;
            out.insert(name, t);
        }
    }
    Ok(out)
}

/// A tensor's values as a flat NumPy array (moved, not copied, from the decoded message;
/// strings as a list of str).
fn tensor_to_py<'py>(py: Python<'py>, t: Tensor) -> PyResult<Bound<'py, PyAny>> {
    Ok(match t.payload {
        None => numpy::PyArray1::<f32>::zeros(py, 0, false).into_any(),
        Some(Payload::Floats(a)) => a.array.into_pyarray(py).into_any(),
        Some(Payload::Doubles(a)) => a.array.into_pyarray(py).into_any(),
        Some(Payload::Int8s(a)) => a
            .array
            .into_iter()
            .map(|b| b as i8)
            .collect::<Vec<i8>>()
            .into_pyarray(py)
            .into_any(),
        Some(Payload::Int32s(a)) => a.array.into_pyarray(py).into_any(),
        Some(Payload::Int64s(a)) => a.array.into_pyarray(py).into_any(),
        Some(Payload::Uint8s(a)) => a.array.into_pyarray(py).into_any(),
        Some(Payload::Uint32s(a)) => a.array.into_pyarray(py).into_any(),
        Some(Payload::Uint64s(a)) => a.array.into_pyarray(py).into_any(),
        Some(Payload::Bools(a)) => a.array.into_pyarray(py).into_any(),
        Some(Payload::Strings(a)) => PyList::new(py, a.array)?.into_any(),
        Some(Payload::Protos(a)) => {
            PyList::new(py, a.array.into_iter().map(|m| PyBytes::new(py, &m.value)))?.into_any()
        }
    })
}

fn specs_to_py<'py>(
    py: Python<'py>,
    specs: Option<ActionObservationSpecs>,
) -> PyResult<Bound<'py, PyAny>> {
    let Some(specs) = specs else {
        return Ok(py.None().into_bound(py));
    };
    let part = |m: BTreeMap<u64, TensorSpec>| -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (uid, s) in m {
            d.set_item(uid, (s.name, s.dtype, s.shape))?;
        }
        Ok(d)
    };
    let out = PyDict::new(py);
    out.set_item("actions", part(specs.actions)?)?;
    out.set_item("observations", part(specs.observations)?)?;
    Ok(out.into_any())
}

fn answer_to_py<'py>(py: Python<'py>, a: Answer) -> PyResult<Bound<'py, PyAny>> {
    Ok(match a {
        Answer::WorldName(n) => PyString::new(py, &n).into_any(),
        Answer::Specs(s) => specs_to_py(py, s)?,
        Answer::Step(state, obs) => {
            let d = PyDict::new(py);
            for (uid, t) in obs {
                d.set_item(uid, tensor_to_py(py, t)?)?;
            }
            (state, d).into_pyobject(py)?.into_any()
        }
        Answer::Empty => py.None().into_bound(py),
        Answer::Raw(b) => PyBytes::new(py, &b).into_any(),
    })
}

fn step_request(
    actions: Option<PyReadonlyArrayDyn<'_, i32>>,
    requested: Vec<u64>,
    action_uid: u64,
) -> Req {
    let mut a = BTreeMap::new();
    if let Some(x) = actions {
        let shape: Vec<i32> = x.shape().iter().map(|&d| d as i32).collect();
        let values: Vec<i32> = match x.as_slice() {
            Ok(s) => s.to_vec(),
            Err(_) => x.as_array().iter().copied().collect(),
        };
        a.insert(
            action_uid,
            Tensor {
                payload: Some(Payload::Int32s(sixaxis_server::proto::tensor::Int32Array {
                    array: values,
                })),
                shape,
            },
        );
    }
    Req::Step(StepRequest {
        actions: a,
        requested_observations: requested,
    })
}

// The Python class ----------------------------------------------------------------------------

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
