//! A tiny tonic client of the env server: single-env Step round trips (p50 / p99) and the
//! env steps per second of one batched world (docs/SERVER.md "What a step costs").
//!
//! ```sh
//! cargo run --release -p sixaxis-server --example step_latency              # in-process server
//! cargo run --release -p sixaxis-server --example step_latency -- 127.0.0.1:50051 2000 1024
//! ```
//! Arguments: the server's address (or `-` for one started in this process), the number of
//! single-env steps, the lanes of the batched world.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use sixaxis_server::proto::environment::{Request as Req, Response as Resp};
use sixaxis_server::proto::rpc::environment_client::EnvironmentClient;
use sixaxis_server::proto::tensor::{Int32Array, Int64Array, Payload};
use sixaxis_server::proto::*;
use sixaxis_server::{BackgroundServer, ServerConfig};
use tokio::sync::mpsc;
use tokio_stream::wrappers::ReceiverStream;

struct Stream {
    tx: mpsc::Sender<EnvironmentRequest>,
    rx: tonic::Streaming<EnvironmentResponse>,
}

impl Stream {
    async fn send(&mut self, r: Req) -> Resp {
        self.tx
            .send(EnvironmentRequest { payload: Some(r) })
            .await
            .expect("send");
        let resp = self.rx.message().await.expect("response").expect("open");
        match resp.payload.expect("payload") {
            Resp::Error(e) => panic!("server error: {}", e.message),
            r => r,
        }
    }

    async fn world(&mut self, n: i64) {
        let mut settings = BTreeMap::new();
        settings.insert(
            "num_envs".to_string(),
            Tensor {
                payload: Some(Payload::Int64s(Int64Array { array: vec![n] })),
                shape: vec![],
            },
        );
        let Resp::CreateWorld(c) = self
            .send(Req::CreateWorld(CreateWorldRequest { settings }))
            .await
        else {
            panic!("no world")
        };
        self.send(Req::JoinWorld(JoinWorldRequest {
            world_name: c.world_name,
            settings: BTreeMap::new(),
        }))
        .await;
    }
}

fn step(actions: Vec<i32>, n: usize) -> Req {
    let mut a = BTreeMap::new();
    a.insert(
        1,
        Tensor {
            payload: Some(Payload::Int32s(Int32Array { array: actions })),
            shape: if n == 1 { vec![] } else { vec![n as i32] },
        },
    );
    Req::Step(StepRequest {
        actions: a,
        requested_observations: vec![1, 2, 3, 6, 7],
    })
}

async fn connect(address: &str) -> Stream {
    let mut c = EnvironmentClient::connect(format!("http://{address}"))
        .await
        .expect("connects")
        .max_decoding_message_size(64 << 20);
    let (tx, rx) = mpsc::channel(4);
    let rx = c
        .process(ReceiverStream::new(rx))
        .await
        .expect("stream")
        .into_inner();
    Stream { tx, rx }
}

fn percentile(sorted: &[Duration], p: f64) -> f64 {
    let i = ((sorted.len() as f64 - 1.0) * p).round() as usize;
    sorted[i].as_secs_f64() * 1e6
}

#[tokio::main]
async fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let _local;
    let address = match args.first().map(String::as_str) {
        None | Some("-") => {
            _local = BackgroundServer::start(ServerConfig::default()).expect("server starts");
            _local.address().to_string()
        }
        Some(a) => a.to_string(),
    };
    let steps: usize = args.get(1).and_then(|v| v.parse().ok()).unwrap_or(5000);
    let lanes: usize = args.get(2).and_then(|v| v.parse().ok()).unwrap_or(1024);

    let mut s = connect(&address).await;
    s.world(1).await;
    s.send(step(vec![0], 1)).await;
    let mut times = Vec::with_capacity(steps);
    for i in 0..steps + 200 {
        let t = Instant::now();
        s.send(step(vec![(i % 6) as i32], 1)).await;
        if i >= 200 {
            times.push(t.elapsed());
        }
    }
    times.sort();
    println!(
        "single env: {steps} Step round trips, p50 {:.1} us, p99 {:.1} us",
        percentile(&times, 0.5),
        percentile(&times, 0.99)
    );

    let mut b = connect(&address).await;
    b.world(lanes as i64).await;
    b.send(step(vec![0; lanes], lanes)).await;
    let acts: Vec<i32> = (0..lanes as i32).map(|i| i % 6).collect();
    let t = Instant::now();
    let mut calls = 0usize;
    while t.elapsed() < Duration::from_secs(3) {
        b.send(step(acts.clone(), lanes)).await;
        calls += 1;
    }
    let secs = t.elapsed().as_secs_f64();
    println!(
        "batched world of {lanes} lanes: {calls} Steps in {secs:.2} s, {:.0} env steps/s ({:.1} us per Step)",
        (calls * lanes) as f64 / secs,
        secs * 1e6 / calls as f64
    );
}
