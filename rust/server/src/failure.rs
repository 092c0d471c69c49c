//! A request's failure: a gRPC code and a message, sent back as the `google.rpc.Status` of
//! `EnvironmentResponse.error` (the stream goes on).

use tonic::Code;

use crate::proto::{environment, EnvironmentResponse, RpcStatus};

/// Why a request failed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Failure {
    /// The gRPC code.
    pub code: Code,
    /// The message (names the setting or field and the value at fault).
    pub message: String,
}

impl Failure {
    /// A failure with this code and message.
    pub fn new(code: Code, message: impl Into<String>) -> Failure {
        Failure {
            code,
            message: message.into(),
        }
    }

    /// INVALID_ARGUMENT in the core's words: "invalid argument `name` = value: reason".
    pub fn argument(name: &str, value: impl std::fmt::Display, reason: impl AsRef<str>) -> Failure {
        Failure::from(sixaxis_core::Error::argument(name, value, reason.as_ref()))
    }

    /// The response that carries this failure.
    pub fn response(&self) -> EnvironmentResponse {
        EnvironmentResponse {
            payload: Some(environment::Response::Error(RpcStatus {
                code: self.code as i32,
                message: self.message.clone(),
                details: Vec::new(),
            })),
        }
    }
}

impl From<sixaxis_core::Error> for Failure {
    fn from(e: sixaxis_core::Error) -> Failure {
        use sixaxis_core::Error as E;
        let code = match e {
            E::ScenarioNotFound { .. } => Code::NotFound,
            E::Io { .. } => Code::Internal,
            _ => Code::InvalidArgument,
        };
        Failure::new(code, e.to_string())
    }
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:?}: {}", self.code, self.message)
    }
}
