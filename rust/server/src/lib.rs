//! The SixAxisAvoid env server: DeepMind's dm_env_rpc v1 protocol over gRPC (tonic), its
//! worlds stepped by `sixaxis-core`'s native batch (docs/SERVER.md).
//!
//! One service, `dm_env_rpc.v1.Environment`, with one bidirectional stream method,
//! `Process`: a client creates worlds (CreateWorld; settings as the Gymnasium env's
//! keywords, checked by the core's option table), joins one (JoinWorld → specs), and steps
//! it (Step), resets it (Reset, ResetWorld), leaves and destroys it. Errors come back as
//! `google.rpc.Status` in `EnvironmentResponse.error` and the stream goes on.
//!
//! Entry points:
//! - [`bind`] then [`BoundServer::serve`] — a server in the caller's tokio runtime (the
//!   `sixaxis serve` command).
//! - [`BackgroundServer::start`] — a server on its own thread (the Python binding's
//!   `sixaxis_avoid.serve`).
//! - [`proto`] — the protocol's messages (our own prost structs) and the generated tonic
//!   server and client ([`proto::rpc`]).
//! - [`world`] — a world's settings, specs, uids and step semantics.
//! - [`seeding`] — lane seeds as the Python envs derive them from a Gymnasium seed.

pub mod failure;
pub mod proto;
pub mod seeding;
pub mod server;
pub mod service;
pub mod world;

pub use failure::Failure;
pub use server::{
    bind, seconds, BackgroundServer, BoundServer, Listen, ServerConfig, Stats, TlsFiles,
};
pub use service::Limits;
