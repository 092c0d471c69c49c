//! The client's errors: [`ClientError`] (what went wrong, decoded without the GIL) and the
//! one mapping to the Python exceptions of the grpcio transport ([`to_py`],
//! python/sixaxis_avoid/remote/_session.py). Timeouts in the messages are in seconds.

use pyo3::exceptions::{PyConnectionError, PyPermissionError, PyTimeoutError};
use pyo3::prelude::*;

use crate::errors::{invalid_argument, invalid_argument_message};

/// The gRPC status code names (as grpcio's `StatusCode` names them).
pub(super) fn code_name(code: i32) -> String {
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
pub(super) fn seconds(s: f64) -> String {
    if s.is_finite() && s.fract() == 0.0 {
        format!("{s:.1}")
    } else {
        format!("{s}")
    }
}

/// What went wrong, mapped to a Python exception by [`to_py`].
#[derive(Clone, Debug)]
pub(super) enum ClientError {
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
    /// The connection failed before the call's headers and the server answers a plaintext
    /// HTTP/2 preface in TLS: a TLS server, which this transport cannot talk to.
    PlaintextToTls {
        address: String,
        what: String,
        code: i32,
        details: String,
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
pub(super) fn to_py(py: Python<'_>, err: ClientError) -> PyErr {
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
        ClientError::PlaintextToTls {
            address,
            what,
            code,
            details,
        } => PyConnectionError::new_err(format!(
            "the env server at {address} ended the session during {what} ({}: {details}): \
             it answers in TLS (a server started with --tls-cert/--tls-key), and this \
             client speaks plaintext HTTP/2; pass \
             credentials=grpc.ssl_channel_credentials(root_certificates=...) to connect over \
             TLS (it selects transport=\"grpc\"; docs/SERVER.md \"Security\")",
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
pub(super) fn server_error(
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
