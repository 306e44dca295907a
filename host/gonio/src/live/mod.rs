//! The live view of a running scan: a page on 127.0.0.1 (one HTML file,
//! its script inline, no build step) fed by server-sent events, and the
//! requests its buttons and `gonio pause|continue|abort DIR` send. axum
//! serves it on the scan's own runtime; [`Live`] is the scan's side.
//!
//! `GET /` the page; `GET /events` the stream (a `snapshot` event with
//! every sample so far, then `update`s; a page that falls behind gets a new
//! snapshot); `GET /api/state` the snapshot as JSON; `POST /api/pause`,
//! `/api/continue`, `/api/abort`.

use anyhow::{Context, Result};
use axum::extract::State;
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{Html, IntoResponse, Json};
use axum::routing::{get, post};
use axum::Router;
use futures_util::stream::{self, Stream, StreamExt};
use gonio_acquire::scan::live::Live;
use std::convert::Infallible;
use std::net::SocketAddr;
use tokio_stream::wrappers::errors::BroadcastStreamRecvError;
use tokio_stream::wrappers::BroadcastStream;

static PAGE: &str = include_str!("page.html");

/// Serves `live` at `addr` (port 0: any free one) on the current runtime;
/// returns the page's address.
pub async fn serve(live: Live, addr: SocketAddr) -> Result<String> {
    let listener = tokio::net::TcpListener::bind(addr)
        .await
        .with_context(|| format!("the live view cannot listen on {addr}"))?;
    let url = format!("http://{}/", listener.local_addr().context("the live view's address")?);
    let app = Router::new()
        .route("/", get(|| async { Html(PAGE) }))
        .route("/events", get(events))
        .route("/api/state", get(state))
        .route(
            "/api/pause",
            post(|State(l): State<Live>| async move {
                l.pause();
                accepted(&l)
            }),
        )
        .route(
            "/api/continue",
            post(|State(l): State<Live>| async move {
                l.resume();
                accepted(&l)
            }),
        )
        .route(
            "/api/abort",
            post(|State(l): State<Live>| async move {
                l.abort();
                accepted(&l)
            }),
        )
        .with_state(live);
    tokio::spawn(async move {
        // The server ends with the process; an error here (the socket
        // failing) leaves the scan running without its page.
        let _ = axum::serve(listener, app).await;
    });
    Ok(url)
}

fn accepted(live: &Live) -> impl IntoResponse {
    Json(serde_json::json!({ "accepted": true, "state": live.current_state() }))
}

async fn state(State(live): State<Live>) -> impl IntoResponse {
    Json(live.subscribe().0)
}

async fn events(State(live): State<Live>) -> Sse<impl Stream<Item = Result<Event, Infallible>>> {
    let (seen, rx) = live.subscribe();
    let snapshot = |seen: &gonio_acquire::scan::live::Seen| Event::default().event("snapshot").json_data(seen).unwrap_or_default();
    let first = stream::once(std::future::ready(Ok(snapshot(&seen))));
    let rest = BroadcastStream::new(rx).map(move |u| {
        Ok(match u {
            Ok(u) => Event::default().event("update").json_data(&u).unwrap_or_default(),
            // Fallen behind: everything again.
            Err(BroadcastStreamRecvError::Lagged(_)) => snapshot(&live.subscribe().0),
        })
    });
    Sse::new(first.chain(rest)).keep_alive(KeepAlive::default())
}
