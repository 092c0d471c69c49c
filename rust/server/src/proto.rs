//! The dm_env_rpc v1 messages, written here as prost structs from the protocol's wire format
//! (package `dm_env_rpc.v1`; docs/SERVER.md, "The protocol"): every message name and field
//! number is the protocol's, so any dm_env_rpc client reads and writes them.
//!
//! Maps (`map<K, V>` in the protocol) are repeated key/value entry messages on the wire,
//! which prost's `map`/`btree_map` fields encode and decode. `google.protobuf.Any` and
//! `google.rpc.Status` are written here too ([`Any`], [`RpcStatus`]).

use std::collections::BTreeMap;

/// `google.protobuf.Any`: a message of any type, by its type URL.
#[derive(Clone, PartialEq, prost::Message)]
pub struct Any {
    /// The type's URL (`type.googleapis.com/package.Message`).
    #[prost(string, tag = "1")]
    pub type_url: String,
    /// The encoded message.
    #[prost(bytes = "vec", tag = "2")]
    pub value: Vec<u8>,
}

/// `google.rpc.Status`: an error, its gRPC code and message.
#[derive(Clone, PartialEq, prost::Message)]
pub struct RpcStatus {
    /// The gRPC status code (`google.rpc.Code`: 3 INVALID_ARGUMENT, 5 NOT_FOUND, ...).
    #[prost(int32, tag = "1")]
    pub code: i32,
    /// What went wrong, for a person.
    #[prost(string, tag = "2")]
    pub message: String,
    /// Details (unused by this server).
    #[prost(message, repeated, tag = "3")]
    pub details: Vec<Any>,
}

/// `dm_env_rpc.v1.DataType`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, prost::Enumeration)]
#[repr(i32)]
pub enum DataType {
    /// Not a type.
    InvalidDataType = 0,
    /// float32.
    Float = 1,
    /// float64.
    Double = 2,
    /// int8.
    Int8 = 3,
    /// int32.
    Int32 = 4,
    /// int64.
    Int64 = 5,
    /// uint8.
    Uint8 = 6,
    /// uint32.
    Uint32 = 7,
    /// uint64.
    Uint64 = 8,
    /// bool.
    Bool = 9,
    /// UTF-8 string.
    String = 10,
    /// `google.protobuf.Any`.
    Proto = 11,
}

/// `dm_env_rpc.v1.EnvironmentStateType`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, prost::Enumeration)]
#[repr(i32)]
pub enum EnvironmentStateType {
    /// Not a state.
    InvalidEnvironmentState = 0,
    /// The episode runs.
    Running = 1,
    /// The episode ended by the environment (here: the target was reached).
    Terminated = 2,
    /// The episode was cut short (here: truncated at `max_episode_steps`).
    Interrupted = 3,
}

/// The payload arrays of a [`Tensor`] (`Tensor.FloatArray`, ...).
pub mod tensor {
    /// `Tensor.FloatArray`.
    #[derive(Clone, PartialEq, prost::Message)]
    pub struct FloatArray {
        /// Values.
        #[prost(float, repeated, tag = "1")]
        pub array: Vec<f32>,
    }
    /// `Tensor.DoubleArray`.
    #[derive(Clone, PartialEq, prost::Message)]
    pub struct DoubleArray {
        /// Values.
        #[prost(double, repeated, tag = "1")]
        pub array: Vec<f64>,
    }
    /// `Tensor.Int8Array` (bytes on the wire).
    #[derive(Clone, PartialEq, prost::Message)]
    pub struct Int8Array {
        /// Values, one byte each (two's complement).
        #[prost(bytes = "vec", tag = "1")]
        pub array: Vec<u8>,
    }
    /// `Tensor.Int32Array`.
    #[derive(Clone, PartialEq, prost::Message)]
    pub struct Int32Array {
        /// Values.
        #[prost(int32, repeated, tag = "1")]
        pub array: Vec<i32>,
    }
    /// `Tensor.Int64Array`.
    #[derive(Clone, PartialEq, prost::Message)]
    pub struct Int64Array {
        /// Values.
        #[prost(int64, repeated, tag = "1")]
        pub array: Vec<i64>,
    }
    /// `Tensor.Uint8Array` (bytes on the wire).
    #[derive(Clone, PartialEq, prost::Message)]
    pub struct Uint8Array {
        /// Values.
        #[prost(bytes = "vec", tag = "1")]
        pub array: Vec<u8>,
    }
    /// `Tensor.Uint32Array`.
    #[derive(Clone, PartialEq, prost::Message)]
    pub struct Uint32Array {
        /// Values.
        #[prost(uint32, repeated, tag = "1")]
        pub array: Vec<u32>,
    }
    /// `Tensor.Uint64Array`.
    #[derive(Clone, PartialEq, prost::Message)]
    pub struct Uint64Array {
        /// Values.
        #[prost(uint64, repeated, tag = "1")]
        pub array: Vec<u64>,
    }
    /// `Tensor.BoolArray`.
    #[derive(Clone, PartialEq, prost::Message)]
    pub struct BoolArray {
        /// Values.
        #[prost(bool, repeated, tag = "1")]
        pub array: Vec<bool>,
    }
    /// `Tensor.StringArray`.
    #[derive(Clone, PartialEq, prost::Message)]
    pub struct StringArray {
        /// Values.
        #[prost(string, repeated, tag = "1")]
        pub array: Vec<String>,
    }
    /// `Tensor.ProtoArray`.
    #[derive(Clone, PartialEq, prost::Message)]
    pub struct ProtoArray {
        /// Values.
        #[prost(message, repeated, tag = "1")]
        pub array: Vec<super::Any>,
    }

    /// The `payload` oneof of a [`super::Tensor`].
    #[derive(Clone, PartialEq, prost::Oneof)]
    pub enum Payload {
        /// float32 values.
        #[prost(message, tag = "1")]
        Floats(FloatArray),
        /// float64 values.
        #[prost(message, tag = "2")]
        Doubles(DoubleArray),
        /// int8 values.
        #[prost(message, tag = "3")]
        Int8s(Int8Array),
        /// int32 values.
        #[prost(message, tag = "4")]
        Int32s(Int32Array),
        /// int64 values.
        #[prost(message, tag = "5")]
        Int64s(Int64Array),
        /// uint8 values.
        #[prost(message, tag = "6")]
        Uint8s(Uint8Array),
        /// uint32 values.
        #[prost(message, tag = "7")]
        Uint32s(Uint32Array),
        /// uint64 values.
        #[prost(message, tag = "8")]
        Uint64s(Uint64Array),
        /// bool values.
        #[prost(message, tag = "9")]
        Bools(BoolArray),
        /// strings.
        #[prost(message, tag = "10")]
        Strings(StringArray),
        /// messages.
        #[prost(message, tag = "11")]
        Protos(ProtoArray),
    }
}

/// `dm_env_rpc.v1.Tensor`: a flat payload (row-major) and its shape. An empty shape is a
/// scalar; one dimension may be -1 (inferred from the payload); a payload of one value is
/// broadcast to the shape.
#[derive(Clone, PartialEq, prost::Message)]
pub struct Tensor {
    /// The values.
    #[prost(oneof = "tensor::Payload", tags = "1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11")]
    pub payload: Option<tensor::Payload>,
    /// The dimensions.
    #[prost(int32, repeated, tag = "15")]
    pub shape: Vec<i32>,
}

/// The bounds of a numeric [`TensorSpec`].
pub mod tensor_spec {
    use super::tensor::{
        DoubleArray, FloatArray, Int32Array, Int64Array, Int8Array, Uint32Array, Uint64Array,
        Uint8Array,
    };

    /// `TensorSpec.Value`: a bound, one value (broadcast) or one per element.
    #[derive(Clone, PartialEq, prost::Message)]
    pub struct Value {
        /// The values.
        #[prost(oneof = "ValuePayload", tags = "9, 10, 11, 12, 13, 14, 15, 16")]
        pub payload: Option<ValuePayload>,
    }

    /// The `payload` oneof of a [`Value`].
    #[derive(Clone, PartialEq, prost::Oneof)]
    pub enum ValuePayload {
        /// float32.
        #[prost(message, tag = "9")]
        Floats(FloatArray),
        /// float64.
        #[prost(message, tag = "10")]
        Doubles(DoubleArray),
        /// int8.
        #[prost(message, tag = "11")]
        Int8s(Int8Array),
        /// int32.
        #[prost(message, tag = "12")]
        Int32s(Int32Array),
        /// int64.
        #[prost(message, tag = "13")]
        Int64s(Int64Array),
        /// uint8.
        #[prost(message, tag = "14")]
        Uint8s(Uint8Array),
        /// uint32.
        #[prost(message, tag = "15")]
        Uint32s(Uint32Array),
        /// uint64.
        #[prost(message, tag = "16")]
        Uint64s(Uint64Array),
    }
}

/// `dm_env_rpc.v1.TensorSpec`: what an action or observation tensor holds.
#[derive(Clone, PartialEq, prost::Message)]
pub struct TensorSpec {
    /// Unique name among the actions (or the observations).
    #[prost(string, tag = "1")]
    pub name: String,
    /// The shape (-1: variable).
    #[prost(int32, repeated, tag = "2")]
    pub shape: Vec<i32>,
    /// The element type.
    #[prost(enumeration = "DataType", tag = "3")]
    pub dtype: i32,
    /// Inclusive lower bound.
    #[prost(message, optional, tag = "4")]
    pub min: Option<tensor_spec::Value>,
    /// Inclusive upper bound.
    #[prost(message, optional, tag = "5")]
    pub max: Option<tensor_spec::Value>,
}

/// Settings of a request: name → tensor.
pub type Settings = BTreeMap<String, Tensor>;

/// `CreateWorldRequest`.
#[derive(Clone, PartialEq, prost::Message)]
pub struct CreateWorldRequest {
    /// The world's settings.
    #[prost(btree_map = "string, message", tag = "1")]
    pub settings: Settings,
}
/// `CreateWorldResponse`.
#[derive(Clone, PartialEq, prost::Message)]
pub struct CreateWorldResponse {
    /// The new world's name.
    #[prost(string, tag = "1")]
    pub world_name: String,
}
/// `ActionObservationSpecs`: uid → spec.
#[derive(Clone, PartialEq, prost::Message)]
pub struct ActionObservationSpecs {
    /// Action specs by uid.
    #[prost(btree_map = "uint64, message", tag = "1")]
    pub actions: BTreeMap<u64, TensorSpec>,
    /// Observation specs by uid.
    #[prost(btree_map = "uint64, message", tag = "2")]
    pub observations: BTreeMap<u64, TensorSpec>,
}
/// `JoinWorldRequest`.
#[derive(Clone, PartialEq, prost::Message)]
pub struct JoinWorldRequest {
    /// The world to join.
    #[prost(string, tag = "1")]
    pub world_name: String,
    /// Join settings (none are accepted here).
    #[prost(btree_map = "string, message", tag = "2")]
    pub settings: Settings,
}
/// `JoinWorldResponse`.
#[derive(Clone, PartialEq, prost::Message)]
pub struct JoinWorldResponse {
    /// The world's specs.
    #[prost(message, optional, tag = "1")]
    pub specs: Option<ActionObservationSpecs>,
}
/// `StepRequest`.
#[derive(Clone, PartialEq, prost::Message)]
pub struct StepRequest {
    /// Actions by uid.
    #[prost(btree_map = "uint64, message", tag = "1")]
    pub actions: BTreeMap<u64, Tensor>,
    /// The observation uids to send back.
    #[prost(uint64, repeated, tag = "2")]
    pub requested_observations: Vec<u64>,
}
/// `StepResponse`.
#[derive(Clone, PartialEq, prost::Message)]
pub struct StepResponse {
    /// The episode's state after the step.
    #[prost(enumeration = "EnvironmentStateType", tag = "1")]
    pub state: i32,
    /// The requested observations by uid.
    #[prost(btree_map = "uint64, message", tag = "2")]
    pub observations: BTreeMap<u64, Tensor>,
}
/// `ResetRequest`.
#[derive(Clone, PartialEq, prost::Message)]
pub struct ResetRequest {
    /// Reset settings (`seed`).
    #[prost(btree_map = "string, message", tag = "1")]
    pub settings: Settings,
}
/// `ResetResponse`.
#[derive(Clone, PartialEq, prost::Message)]
pub struct ResetResponse {
    /// The world's specs (unchanged).
    #[prost(message, optional, tag = "1")]
    pub specs: Option<ActionObservationSpecs>,
}
/// `ResetWorldRequest`.
#[derive(Clone, PartialEq, prost::Message)]
pub struct ResetWorldRequest {
    /// The world.
    #[prost(string, tag = "1")]
    pub world_name: String,
    /// Settings (`seed`).
    #[prost(btree_map = "string, message", tag = "2")]
    pub settings: Settings,
}
/// `ResetWorldResponse`.
#[derive(Clone, PartialEq, prost::Message)]
pub struct ResetWorldResponse {}
/// `LeaveWorldRequest`.
#[derive(Clone, PartialEq, prost::Message)]
pub struct LeaveWorldRequest {}
/// `LeaveWorldResponse`.
#[derive(Clone, PartialEq, prost::Message)]
pub struct LeaveWorldResponse {}
/// `DestroyWorldRequest`.
#[derive(Clone, PartialEq, prost::Message)]
pub struct DestroyWorldRequest {
    /// The world.
    #[prost(string, tag = "1")]
    pub world_name: String,
}
/// `DestroyWorldResponse`.
#[derive(Clone, PartialEq, prost::Message)]
pub struct DestroyWorldResponse {}

/// The `payload` oneofs of [`EnvironmentRequest`] and [`EnvironmentResponse`].
pub mod environment {
    use super::*;

    /// What an [`EnvironmentRequest`] asks.
    #[derive(Clone, PartialEq, prost::Oneof)]
    pub enum Request {
        /// CreateWorld.
        #[prost(message, tag = "1")]
        CreateWorld(CreateWorldRequest),
        /// JoinWorld.
        #[prost(message, tag = "2")]
        JoinWorld(JoinWorldRequest),
        /// Step.
        #[prost(message, tag = "3")]
        Step(StepRequest),
        /// Reset.
        #[prost(message, tag = "4")]
        Reset(ResetRequest),
        /// ResetWorld.
        #[prost(message, tag = "5")]
        ResetWorld(ResetWorldRequest),
        /// LeaveWorld.
        #[prost(message, tag = "6")]
        LeaveWorld(LeaveWorldRequest),
        /// DestroyWorld.
        #[prost(message, tag = "7")]
        DestroyWorld(DestroyWorldRequest),
        /// A protocol extension (none supported here).
        #[prost(message, tag = "15")]
        Extension(Any),
    }

    /// What an [`EnvironmentResponse`] answers.
    #[derive(Clone, PartialEq, prost::Oneof)]
    pub enum Response {
        /// CreateWorld.
        #[prost(message, tag = "1")]
        CreateWorld(CreateWorldResponse),
        /// JoinWorld.
        #[prost(message, tag = "2")]
        JoinWorld(JoinWorldResponse),
        /// Step.
        #[prost(message, tag = "3")]
        Step(StepResponse),
        /// Reset.
        #[prost(message, tag = "4")]
        Reset(ResetResponse),
        /// ResetWorld.
        #[prost(message, tag = "5")]
        ResetWorld(ResetWorldResponse),
        /// LeaveWorld.
        #[prost(message, tag = "6")]
        LeaveWorld(LeaveWorldResponse),
        /// DestroyWorld.
        #[prost(message, tag = "7")]
        DestroyWorld(DestroyWorldResponse),
        /// A protocol extension.
        #[prost(message, tag = "15")]
        Extension(Any),
        /// The request failed.
        #[prost(message, tag = "16")]
        Error(RpcStatus),
    }
}

/// `EnvironmentRequest`: one request of the `Process` stream.
#[derive(Clone, PartialEq, prost::Message)]
pub struct EnvironmentRequest {
    /// The request.
    #[prost(oneof = "environment::Request", tags = "1, 2, 3, 4, 5, 6, 7, 15")]
    pub payload: Option<environment::Request>,
}

/// `EnvironmentResponse`: the answer to one request, in order.
#[derive(Clone, PartialEq, prost::Message)]
pub struct EnvironmentResponse {
    /// The answer.
    #[prost(oneof = "environment::Response", tags = "1, 2, 3, 4, 5, 6, 7, 15, 16")]
    pub payload: Option<environment::Response>,
}

/// The generated tonic server (`rpc::environment_server`) and client
/// (`rpc::environment_client`) of the service `dm_env_rpc.v1.Environment` (build.rs).
pub mod rpc {
    #![allow(missing_docs, clippy::all)]
    include!(concat!(env!("OUT_DIR"), "/dm_env_rpc.v1.Environment.rs"));
}
