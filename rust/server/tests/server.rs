//! The server through a tonic client: a world's life, errors that keep the stream, clients
//! that vanish, limits, drain.

mod common;

use std::time::Duration;

use common::*;
use sixaxis_server::proto::tensor::Payload;
use sixaxis_server::proto::*;
use sixaxis_server::world::{CELL, OBSERVATION, REWARD, TERMINATED};
use sixaxis_server::{BackgroundServer, Limits, ServerConfig};
use tonic::Code;

fn start(limits: Limits) -> BackgroundServer {
    BackgroundServer::start(ServerConfig {
        limits,
        ..ServerConfig::default()
    })
    .expect("starts")
}

async fn wait_for(cond: impl Fn() -> bool) -> bool {
    for _ in 0..300 {
        if cond() {
            return true;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    cond()
}

#[tokio::test]
async fn a_world_steps_and_errors_keep_the_stream() {
    let s = start(Limits::default());
    let mut c = Client::connect(s.address()).await;
    let name = c
        .create(settings(&[("num_envs", int(4)), ("seed", int(9))]))
        .await
        .unwrap();
    let specs = c.join(&name).await.unwrap();
    assert_eq!(specs.actions[&1].shape, vec![4]);
    assert_eq!(specs.observations[&OBSERVATION].shape, vec![4, 13]);
    // The first Step resets: its actions are ignored, even a bad one.
    let r = c
        .step(Some(actions(&[9, 9, 9, 9])), &[OBSERVATION, REWARD])
        .await
        .unwrap();
    assert_eq!(r.state, EnvironmentStateType::Running as i32);
    match &r.observations[&REWARD].payload {
        Some(Payload::Doubles(d)) => assert_eq!(d.array, vec![0.0; 4]),
        other => panic!("{other:?}"),
    }
    let e = c.step(Some(actions(&[0, 1, 7, 0])), &[]).await.unwrap_err();
    assert_eq!(e.code, Code::InvalidArgument as i32);
    assert!(
        e.message.contains("`action` = 7 at index 2"),
        "{}",
        e.message
    );
    let e = c.step(Some(actions(&[0, 1])), &[]).await.unwrap_err();
    assert!(e.message.contains("shape"), "{}", e.message);
    let e = c
        .step(Some(actions(&[0, 1, 2, 3])), &[99])
        .await
        .unwrap_err();
    assert!(e.message.contains("99"), "{}", e.message);
    let r = c
        .step(Some(actions(&[5, 5, 5, 5])), &[CELL, TERMINATED])
        .await
        .unwrap();
    assert_eq!(r.observations.len(), 2);
    let e = c
        .create(settings(&[("reward_scale", int(-1))]))
        .await
        .unwrap_err();
    assert!(e.message.contains("`reward_scale` = -1"), "{}", e.message);
    let e = c.join("world-nope").await.unwrap_err();
    assert_eq!(e.code, Code::FailedPrecondition as i32, "{}", e.message);
    assert!(e.message.contains("already joined"), "{}", e.message);
    let mut other = Client::connect(s.address()).await;
    let e = other.join("world-nope").await.unwrap_err();
    assert_eq!(e.code, Code::NotFound as i32);
    let e = other.join(&name).await.unwrap_err();
    assert!(
        e.message.contains("joined by another connection"),
        "{}",
        e.message
    );
    drop(other);
    assert_eq!(s.stats().worlds(), 1);
    drop(c);
    let freed = wait_for(|| s.stats().worlds() == 0 && s.stats().sessions() == 0).await;
    assert!(
        freed,
        "worlds {} sessions {}",
        s.stats().worlds(),
        s.stats().sessions()
    );
}

#[tokio::test]
async fn vanished_clients_free_their_worlds_and_limits_hold() {
    let s = start(Limits {
        max_sessions: 3,
        max_worlds_per_session: 2,
        max_envs_per_world: 512,
        max_total_envs: 1000,
        ..Limits::default()
    });
    let mut a = Client::connect(s.address()).await;
    let mut b = Client::connect(s.address()).await;
    a.create(settings(&[("num_envs", int(400))])).await.unwrap();
    a.create(settings(&[("num_envs", int(400))])).await.unwrap();
    let e = a.create(settings(&[])).await.unwrap_err();
    assert_eq!(e.code, Code::ResourceExhausted as i32);
    let e = b
        .create(settings(&[("num_envs", int(513))]))
        .await
        .unwrap_err();
    assert!(e.message.contains("`num_envs` = 513"), "{}", e.message);
    let e = b
        .create(settings(&[("num_envs", int(300))]))
        .await
        .unwrap_err();
    assert_eq!(e.code, Code::ResourceExhausted as i32, "{}", e.message);
    b.create(settings(&[("num_envs", int(200))])).await.unwrap();
    assert_eq!(s.stats().worlds(), 3);
    drop(a); // vanishes without LeaveWorld or DestroyWorld
    assert!(wait_for(|| s.stats().worlds() == 1).await);
    b.create(settings(&[("num_envs", int(500))])).await.unwrap();
    drop(b);
    assert!(wait_for(|| s.stats().worlds() == 0 && s.stats().sessions() == 0).await);
}

#[tokio::test]
async fn a_big_world_steps_off_the_reactor_and_a_drain_ends_streams() {
    let mut s = start(Limits::default());
    let mut c = Client::connect(s.address()).await;
    let n = 1024;
    let name = c
        .create(settings(&[
            ("num_envs", int(n)),
            ("scenario", text("paper_simple")),
        ]))
        .await
        .unwrap();
    c.join(&name).await.unwrap();
    c.step(None, &[]).await.unwrap();
    let acts: Vec<i32> = (0..n as i32).map(|i| i % 6).collect();
    for _ in 0..20 {
        let r = c.step(Some(actions(&acts)), &[OBSERVATION]).await.unwrap();
        match &r.observations[&OBSERVATION].payload {
            Some(Payload::Floats(f)) => assert_eq!(f.array.len(), 1024 * 13),
            other => panic!("{other:?}"),
        }
    }
    let t0 = std::time::Instant::now();
    tokio::task::spawn_blocking(move || s.stop())
        .await
        .unwrap()
        .unwrap();
    assert!(t0.elapsed() < Duration::from_secs(5), "{:?}", t0.elapsed());
    // The idle stream was ended by the drain with UNAVAILABLE.
    match c.rx.message().await {
        Err(st) => assert_eq!(st.code(), Code::Unavailable, "{st:?}"),
        Ok(other) => panic!("expected UNAVAILABLE, got {other:?}"),
    }
}

#[tokio::test]
async fn keepalive_keeps_clients_that_answer_and_drops_those_that_do_not() {
    // docs/SERVER.md "Limits": a ping after 1 s of silence, 1 s to answer it.
    let s = start(Limits {
        keepalive_interval: Duration::from_secs(1),
        keepalive_timeout: Duration::from_secs(1),
        ..Limits::default()
    });
    let mut c = Client::connect(s.address()).await;
    let name = c.create(settings(&[("seed", int(1))])).await.unwrap();
    c.join(&name).await.unwrap();
    c.step(None, &[]).await.unwrap();
    // Idle for 4 s with the client's runtime running: its connection answers the pings.
    tokio::time::sleep(Duration::from_secs(4)).await;
    c.step(Some(actions(&[4])), &[REWARD]).await.unwrap();
    assert_eq!(s.stats().worlds(), 1);
    // Idle for 4 s with the runtime blocked, so nobody reads the connection: the ping goes
    // unanswered and the server closes the connection, freeing the world. (Were it kept,
    // the world would stay: the idle timeout is 600 s.)
    std::thread::sleep(Duration::from_secs(4));
    assert!(wait_for(|| s.stats().worlds() == 0 && s.stats().sessions() == 0).await);
    let sent =
        c.tx.send(EnvironmentRequest {
            payload: Some(environment::Request::Step(StepRequest::default())),
        })
        .await;
    let answer = c.rx.message().await;
    assert!(
        sent.is_err() || !matches!(answer, Ok(Some(_))),
        "{answer:?}"
    );
}
