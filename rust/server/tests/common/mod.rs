//! A tonic client of the server for the integration tests.

#![allow(dead_code)]

use std::collections::BTreeMap;

use sixaxis_server::proto::environment::{Request as Req, Response as Resp};
use sixaxis_server::proto::rpc::environment_client::EnvironmentClient;
use sixaxis_server::proto::tensor::{Int32Array, Int64Array, Payload, StringArray};
use sixaxis_server::proto::*;
use tokio::sync::mpsc;
use tokio_stream::wrappers::ReceiverStream;
use tonic::Streaming;

/// One `Process` stream.
pub struct Client {
    pub tx: mpsc::Sender<EnvironmentRequest>,
    pub rx: Streaming<EnvironmentResponse>,
}

impl Client {
    pub async fn connect(address: &str) -> Client {
        let mut c = EnvironmentClient::connect(format!("http://{address}"))
            .await
            .expect("connects");
        let (tx, rx) = mpsc::channel(4);
        let rx = c
            .process(ReceiverStream::new(rx))
            .await
            .expect("stream opens")
            .into_inner();
        Client { tx, rx }
    }

    pub async fn send(&mut self, r: Req) -> Resp {
        self.tx
            .send(EnvironmentRequest { payload: Some(r) })
            .await
            .expect("send");
        self.rx
            .message()
            .await
            .expect("a response")
            .expect("not the end")
            .payload
            .expect("a payload")
    }

    pub async fn create(&mut self, settings: Settings) -> Result<String, RpcStatus> {
        match self
            .send(Req::CreateWorld(CreateWorldRequest { settings }))
            .await
        {
            Resp::CreateWorld(r) => Ok(r.world_name),
            Resp::Error(e) => Err(e),
            other => panic!("unexpected {other:?}"),
        }
    }

    pub async fn join(&mut self, name: &str) -> Result<ActionObservationSpecs, RpcStatus> {
        match self
            .send(Req::JoinWorld(JoinWorldRequest {
                world_name: name.into(),
                settings: BTreeMap::new(),
            }))
            .await
        {
            Resp::JoinWorld(r) => Ok(r.specs.expect("specs")),
            Resp::Error(e) => Err(e),
            other => panic!("unexpected {other:?}"),
        }
    }

    pub async fn step(
        &mut self,
        actions: Option<Tensor>,
        uids: &[u64],
    ) -> Result<StepResponse, RpcStatus> {
        let mut a = BTreeMap::new();
        if let Some(t) = actions {
            a.insert(1, t);
        }
        match self
            .send(Req::Step(StepRequest {
                actions: a,
                requested_observations: uids.to_vec(),
            }))
            .await
        {
            Resp::Step(r) => Ok(r),
            Resp::Error(e) => Err(e),
            other => panic!("unexpected {other:?}"),
        }
    }
}

pub fn int(v: i64) -> Tensor {
    Tensor {
        payload: Some(Payload::Int64s(Int64Array { array: vec![v] })),
        shape: vec![],
    }
}

pub fn text(v: &str) -> Tensor {
    Tensor {
        payload: Some(Payload::Strings(StringArray {
            array: vec![v.into()],
        })),
        shape: vec![],
    }
}

pub fn actions(a: &[i32]) -> Tensor {
    Tensor {
        payload: Some(Payload::Int32s(Int32Array { array: a.to_vec() })),
        shape: if a.len() == 1 {
            vec![]
        } else {
            vec![a.len() as i32]
        },
    }
}

pub fn settings(pairs: &[(&str, Tensor)]) -> Settings {
    pairs
        .iter()
        .map(|(k, v)| (k.to_string(), v.clone()))
        .collect()
}
