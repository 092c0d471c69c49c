//! The `dm_env_rpc.v1.Environment` service: one task per `Process` stream (a session),
//! worlds in a registry shared by the sessions, limits and authentication.
//!
//! - A session answers its requests in order. A failed request is answered with
//!   `EnvironmentResponse.error` and the stream goes on; only a request that cannot be
//!   decoded, an idle stream or the server's shutdown end it.
//! - The worlds a session created are destroyed when it ends, however it ends (the client
//!   closed the stream, vanished, or idled out): `Session`'s `Drop`.
//! - Steps of worlds of at least [`BLOCKING_LANES`] lanes run on tokio's blocking pool, off
//!   the reactor; smaller ones inline (a thread hop costs more than their step).
//! - A panic in a request is caught and answered with INTERNAL; the server goes on.

use std::collections::HashMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::pin::Pin;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use subtle::ConstantTimeEq;
use tokio::sync::{mpsc, watch};
use tokio_stream::wrappers::ReceiverStream;
use tokio_stream::Stream;
use tonic::{Code, Request, Response, Status, Streaming};

use crate::failure::Failure;
use crate::proto::environment::{Request as Req, Response as Resp};
use crate::proto::rpc::environment_server::Environment;
use crate::proto::*;
use crate::world::{gone, reset_settings, ResetSettings, World, WorldSettings};

/// Worlds of at least this many lanes are stepped on the blocking pool.
pub const BLOCKING_LANES: usize = 256;

/// The server's limits (docs/SERVER.md "Limits").
#[derive(Debug, Clone, PartialEq)]
pub struct Limits {
    /// Concurrent `Process` streams.
    pub max_sessions: usize,
    /// Worlds one session may hold at once.
    pub max_worlds_per_session: usize,
    /// Lanes of one world (`num_envs`).
    pub max_envs_per_world: usize,
    /// Lanes of all worlds together.
    pub max_total_envs: usize,
    /// Size of one encoded request or response, bytes.
    pub max_message_bytes: usize,
    /// A stream with no request for this long is closed (its worlds freed).
    pub idle_timeout: Duration,
    /// How often the server sends an HTTP/2 keepalive ping on a connection that sent it
    /// nothing for this long.
    pub keepalive_interval: Duration,
    /// How long a ping may go unanswered before the connection is closed (its streams
    /// ended, their worlds freed).
    pub keepalive_timeout: Duration,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_sessions: 64,
            max_worlds_per_session: 16,
            max_envs_per_world: 65_536,
            max_total_envs: 1 << 21,
            max_message_bytes: 64 << 20,
            idle_timeout: Duration::from_secs(600),
            keepalive_interval: Duration::from_secs(30),
            keepalive_timeout: Duration::from_secs(20),
        }
    }
}

/// One world in the registry.
#[derive(Debug)]
struct Slot {
    name: String,
    owner: u64,
    num_envs: usize,
    /// The session joined to it.
    joined_by: Mutex<Option<u64>>,
    world: Mutex<World>,
}

impl Slot {
    fn run<T>(&self, f: impl FnOnce(&mut World) -> Result<T, Failure>) -> Result<T, Failure> {
        let mut w = self.world.lock().map_err(|_| gone(&self.name))?;
        f(&mut w)
    }
}

/// State shared by the sessions.
#[derive(Debug)]
pub(crate) struct Shared {
    pub(crate) limits: Limits,
    /// `Bearer TOKEN`, if the server wants one.
    expected_auth: Option<Vec<u8>>,
    worlds: Mutex<HashMap<String, Arc<Slot>>>,
    sessions: AtomicUsize,
    total_envs: AtomicUsize,
    next_id: AtomicU64,
    /// Becomes true when the server drains.
    shutdown: watch::Receiver<bool>,
}

impl Shared {
    pub(crate) fn new(
        limits: Limits,
        token: Option<&str>,
        shutdown: watch::Receiver<bool>,
    ) -> Shared {
        Shared {
            limits,
            expected_auth: token.map(|t| format!("Bearer {t}").into_bytes()),
            worlds: Mutex::new(HashMap::new()),
            sessions: AtomicUsize::new(0),
            total_envs: AtomicUsize::new(0),
            next_id: AtomicU64::new(1),
            shutdown,
        }
    }

    fn slot(&self, name: &str) -> Result<Arc<Slot>, Failure> {
        self.worlds
            .lock()
            .expect("the registry lock is never held across a panic")
            .get(name)
            .cloned()
            .ok_or_else(|| {
                Failure::new(
                    Code::NotFound,
                    format!("world `{name}` does not exist (unknown, destroyed, or its creator's connection closed)"),
                )
            })
    }

    fn remove(&self, name: &str) {
        let slot = self
            .worlds
            .lock()
            .expect("the registry lock is never held across a panic")
            .remove(name);
        if let Some(s) = slot {
            self.total_envs.fetch_sub(s.num_envs, Ordering::SeqCst);
        }
    }

    /// Number of live worlds.
    pub(crate) fn world_count(&self) -> usize {
        self.worlds.lock().map(|w| w.len()).unwrap_or(0)
    }

    /// Number of open sessions.
    pub(crate) fn session_count(&self) -> usize {
        self.sessions.load(Ordering::SeqCst)
    }

    /// The authorization check: `authorization: Bearer TOKEN`, compared in constant time
    /// (for a token of the right length: the length itself is not hidden).
    fn authorize(&self, md: &tonic::metadata::MetadataMap) -> Result<(), Status> {
        let Some(want) = &self.expected_auth else {
            return Ok(());
        };
        let got = md
            .get("authorization")
            .map(|v| v.as_bytes())
            .unwrap_or_default();
        if bool::from(got.ct_eq(want.as_slice())) {
            Ok(())
        } else {
            Err(Status::unauthenticated(
                "this server needs the metadata `authorization: Bearer TOKEN` with its token",
            ))
        }
    }
}

/// One `Process` stream's state; dropping it frees what it holds.
struct Session {
    id: u64,
    shared: Arc<Shared>,
    owned: Vec<String>,
    joined: Option<Arc<Slot>>,
}

impl Session {
    fn open(shared: &Arc<Shared>) -> Result<Session, Status> {
        let max = shared.limits.max_sessions;
        let n = shared.sessions.fetch_add(1, Ordering::SeqCst);
        if n >= max {
            shared.sessions.fetch_sub(1, Ordering::SeqCst);
            return Err(Status::resource_exhausted(format!(
                "the server holds its maximum of {max} sessions (--max-sessions); try again later"
            )));
        }
        Ok(Session {
            id: shared.next_id.fetch_add(1, Ordering::SeqCst),
            shared: Arc::clone(shared),
            owned: Vec::new(),
            joined: None,
        })
    }

    fn leave(&mut self) {
        if let Some(slot) = self.joined.take() {
            if let Ok(mut j) = slot.joined_by.lock() {
                if *j == Some(self.id) {
                    *j = None;
                }
            }
        }
    }

    fn joined(&self) -> Result<Arc<Slot>, Failure> {
        let slot = self.joined.clone().ok_or_else(|| {
            Failure::new(
                Code::FailedPrecondition,
                "not joined to a world: send JoinWorld first",
            )
        })?;
        // A world destroyed under us (its creator's connection closed) is gone.
        if self.shared.slot(&slot.name).is_err() {
            return Err(gone(&slot.name));
        }
        Ok(slot)
    }

    async fn handle(&mut self, req: EnvironmentRequest) -> EnvironmentResponse {
        let result = match req.payload {
            None => Err(Failure::argument(
                "payload",
                "none",
                "an EnvironmentRequest must hold one of create_world, join_world, step, reset, reset_world, leave_world, destroy_world",
            )),
            Some(p) => self.dispatch(p).await,
        };
        match result {
            Ok(r) => EnvironmentResponse { payload: Some(r) },
            Err(f) => f.response(),
        }
    }

    async fn dispatch(&mut self, p: Req) -> Result<Resp, Failure> {
        match p {
            Req::CreateWorld(r) => self.create_world(r).await,
            Req::JoinWorld(r) => self.join_world(r),
            Req::Step(r) => self.step(r).await,
            Req::Reset(r) => {
                let reset = reset_settings(&r.settings)?;
                let slot = self.joined()?;
                let specs = slot.run(|w| {
                    w.restart(&reset)?;
                    Ok(w.specs().clone())
                })?;
                Ok(Resp::Reset(ResetResponse { specs: Some(specs) }))
            }
            Req::ResetWorld(r) => {
                let reset = reset_settings(&r.settings)?;
                let slot = self.shared.slot(&r.world_name)?;
                slot.run(|w| w.restart(&reset))?;
                Ok(Resp::ResetWorld(ResetWorldResponse {}))
            }
            Req::LeaveWorld(_) => {
                self.leave();
                Ok(Resp::LeaveWorld(LeaveWorldResponse {}))
            }
            Req::DestroyWorld(r) => {
                let slot = self.shared.slot(&r.world_name)?;
                if slot.owner != self.id {
                    return Err(Failure::new(
                        Code::PermissionDenied,
                        format!("world `{}` was created by another connection; only its creator destroys it", r.world_name),
                    ));
                }
                if slot.joined_by.lock().map(|j| j.is_some()).unwrap_or(false) {
                    return Err(Failure::new(
                        Code::FailedPrecondition,
                        format!("world `{}` is joined: send LeaveWorld first", r.world_name),
                    ));
                }
                self.shared.remove(&r.world_name);
                self.owned.retain(|n| n != &r.world_name);
                Ok(Resp::DestroyWorld(DestroyWorldResponse {}))
            }
            Req::Extension(a) => Err(Failure::new(
                Code::Unimplemented,
                format!(
                    "this server has no protocol extensions (got `{}`)",
                    a.type_url
                ),
            )),
        }
    }

    async fn create_world(&mut self, r: CreateWorldRequest) -> Result<Resp, Failure> {
        let limits = &self.shared.limits;
        if self.owned.len() >= limits.max_worlds_per_session {
            return Err(Failure::new(
                Code::ResourceExhausted,
                format!(
                    "this connection holds its maximum of {} worlds: destroy one first",
                    limits.max_worlds_per_session
                ),
            ));
        }
        let settings = WorldSettings::from_settings(&r.settings)?;
        let n = settings.num_envs;
        if n > limits.max_envs_per_world {
            return Err(Failure {
                code: Code::ResourceExhausted,
                ..Failure::argument(
                    "num_envs",
                    n,
                    format!(
                        "exceeds this server's limit of {} lanes per world (--max-envs-per-world)",
                        limits.max_envs_per_world
                    ),
                )
            });
        }
        let before = self.shared.total_envs.fetch_add(n, Ordering::SeqCst);
        if before + n > limits.max_total_envs {
            self.shared.total_envs.fetch_sub(n, Ordering::SeqCst);
            return Err(Failure {
                code: Code::ResourceExhausted,
                ..Failure::argument(
                    "num_envs",
                    n,
                    format!(
                        "the server's worlds hold {before} of its {} lanes; try fewer or later",
                        limits.max_total_envs
                    ),
                )
            });
        }
        let built = tokio::task::spawn_blocking(move || guarded(|| World::new(&settings))).await;
        let world = match built {
            Ok(Ok(w)) => w,
            Ok(Err(f)) => {
                self.shared.total_envs.fetch_sub(n, Ordering::SeqCst);
                return Err(f);
            }
            Err(e) => {
                self.shared.total_envs.fetch_sub(n, Ordering::SeqCst);
                return Err(Failure::new(
                    Code::Internal,
                    format!("world creation failed: {e}"),
                ));
            }
        };
        let name = format!(
            "world-{}-{:016x}",
            self.shared.next_id.fetch_add(1, Ordering::SeqCst),
            rand::random::<u64>()
        );
        let slot = Arc::new(Slot {
            name: name.clone(),
            owner: self.id,
            num_envs: n,
            joined_by: Mutex::new(None),
            world: Mutex::new(world),
        });
        self.shared
            .worlds
            .lock()
            .expect("the registry lock is never held across a panic")
            .insert(name.clone(), slot);
        self.owned.push(name.clone());
        Ok(Resp::CreateWorld(CreateWorldResponse { world_name: name }))
    }

    fn join_world(&mut self, r: JoinWorldRequest) -> Result<Resp, Failure> {
        if let Some(j) = &self.joined {
            return Err(Failure::new(
                Code::FailedPrecondition,
                format!(
                    "already joined to world `{}`: send LeaveWorld first",
                    j.name
                ),
            ));
        }
        if let Some((key, _)) = r.settings.iter().next() {
            return Err(Failure::argument(
                key,
                "given",
                "JoinWorld takes no settings",
            ));
        }
        let slot = self.shared.slot(&r.world_name)?;
        {
            let mut j = slot.joined_by.lock().map_err(|_| gone(&slot.name))?;
            if j.is_some() {
                return Err(Failure::new(
                    Code::FailedPrecondition,
                    format!("world `{}` is joined by another connection", r.world_name),
                ));
            }
            *j = Some(self.id);
        }
        let specs = slot.run(|w| {
            w.restart(&ResetSettings::default())?;
            Ok(w.specs().clone())
        });
        let specs = match specs {
            Ok(s) => s,
            Err(f) => {
                if let Ok(mut j) = slot.joined_by.lock() {
                    *j = None;
                }
                return Err(f);
            }
        };
        self.joined = Some(slot);
        Ok(Resp::JoinWorld(JoinWorldResponse { specs: Some(specs) }))
    }

    async fn step(&mut self, r: StepRequest) -> Result<Resp, Failure> {
        let slot = self.joined()?;
        let out = if slot.num_envs >= BLOCKING_LANES {
            tokio::task::spawn_blocking(move || guarded(|| slot.run(|w| w.step(&r))))
                .await
                .map_err(|e| Failure::new(Code::Internal, format!("step failed: {e}")))?
        } else {
            guarded(|| slot.run(|w| w.step(&r)))
        }?;
        Ok(Resp::Step(out))
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        self.leave();
        for name in std::mem::take(&mut self.owned) {
            self.shared.remove(&name);
        }
        self.shared.sessions.fetch_sub(1, Ordering::SeqCst);
    }
}

/// `f()`, a panic answered as INTERNAL.
fn guarded<T>(f: impl FnOnce() -> Result<T, Failure>) -> Result<T, Failure> {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|p| {
        let what = p
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| p.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "a panic".into());
        Err(Failure::new(
            Code::Internal,
            format!("the server failed at this request (a bug; please report it): {what}"),
        ))
    })
}

/// The service (cheap to clone: it holds the shared state).
#[derive(Debug, Clone)]
pub struct EnvService {
    pub(crate) shared: Arc<Shared>,
}

type ResponseStream = Pin<Box<dyn Stream<Item = Result<EnvironmentResponse, Status>> + Send>>;

#[tonic::async_trait]
impl Environment for EnvService {
    type ProcessStream = ResponseStream;

    async fn process(
        &self,
        request: Request<Streaming<EnvironmentRequest>>,
    ) -> Result<Response<Self::ProcessStream>, Status> {
        self.shared.authorize(request.metadata())?;
        if *self.shared.shutdown.borrow() {
            return Err(Status::unavailable("the server is shutting down"));
        }
        let session = Session::open(&self.shared)?;
        let mut inbound = request.into_inner();
        let (tx, rx) = mpsc::channel(4);
        let idle = self.shared.limits.idle_timeout;
        let mut shutdown = self.shared.shutdown.clone();
        tokio::spawn(async move {
            let mut session = session;
            loop {
                let next = tokio::select! {
                    r = tokio::time::timeout(idle, inbound.message()) => r,
                    _ = async { let _ = shutdown.wait_for(|s| *s).await; } => {
                        let _ = tx.send(Err(Status::unavailable("the server is shutting down"))).await;
                        break;
                    }
                };
                match next {
                    Err(_) => {
                        let _ = tx
                            .send(Err(Status::deadline_exceeded(format!(
                                "no request for {} s: the session is closed and its worlds freed",
                                idle.as_secs_f64()
                            ))))
                            .await;
                        break;
                    }
                    Ok(Err(status)) => {
                        // A request that cannot be decoded (or a broken stream): answered,
                        // then the stream ends; other sessions are untouched.
                        let f = Failure::new(
                            Code::InvalidArgument,
                            format!(
                                "malformed request, the stream is closed: {}",
                                status.message()
                            ),
                        );
                        let _ = tx.send(Ok(f.response())).await;
                        let _ = tx.send(Err(Status::invalid_argument(f.message))).await;
                        break;
                    }
                    Ok(Ok(None)) => break,
                    Ok(Ok(Some(req))) => {
                        let resp = session.handle(req).await;
                        if tx.send(Ok(resp)).await.is_err() {
                            break;
                        }
                    }
                }
            }
            drop(session);
        });
        Ok(Response::new(Box::pin(ReceiverStream::new(rx))))
    }
}
