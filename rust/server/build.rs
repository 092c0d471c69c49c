//! Generates the tonic server and client of `dm_env_rpc.v1.Environment` with tonic-build's
//! `manual` builder: the messages are our own prost structs (src/proto.rs), so no .proto
//! file and no protoc are needed.

fn main() {
    let process = tonic_build::manual::Method::builder()
        .name("process")
        .route_name("Process")
        .input_type("crate::proto::EnvironmentRequest")
        .output_type("crate::proto::EnvironmentResponse")
        .codec_path("tonic_prost::ProstCodec")
        .client_streaming()
        .server_streaming()
        .build();
    let service = tonic_build::manual::Service::builder()
        .name("Environment")
        .package("dm_env_rpc.v1")
        .method(process)
        .build();
    tonic_build::manual::Builder::new().compile(&[service]);
}
