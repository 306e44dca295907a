//! The live view of a running scan: a page on 127.0.0.1 (one HTML file,
//! its script inline, no build step) fed by server-sent events, and the
//! requests its buttons and `gonio pause|continue|abort DIR` send. axum
//! serves it on the scan's own runtime; [`Live`] is the scan's side.
//!
//! `GET /` the page; `GET /events` the stream (a `snapshot` event with
//! every sample so far, then `update`s; a page that falls behind gets a new
//! snapshot); `GET /api/state` the snapshot as JSON; `POST /api/pause`,
//! `/api/continue`, `/api/abort`.
//!
//! Only its user drives it ([`admitted`]), as notebook servers guard
//! theirs: any page in the user's browser can send requests to 127.0.0.1,
//! and, by DNS rebinding, read the answers. So every request must name
//! the printed address as its `Host` (a rebound name does not), carry the
//! scan's token (in the printed URL and in `DIR/live.json`, which only the
//! user can read), and a POST must come from the page's own origin, with
//! the token in a header and a JSON body: a cross-origin page can send
//! neither without a preflight, which this server does not answer.

use super::live::{Live, Served};
use crate::operator::Operator;
use anyhow::bail;
mod remote;

pub use remote::{ask, Steer};

use anyhow::{Context, Result};
use axum::extract::{Request, State};
use axum::http::{header, Method, StatusCode};
use axum::middleware::{self, Next};
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{Html, IntoResponse, Json, Response};
use axum::routing::{get, post};
use axum::Router;
use futures_util::stream::{self, Stream, StreamExt};
use std::convert::Infallible;
use std::net::SocketAddr;
use std::sync::Arc;
use tokio_stream::wrappers::errors::BroadcastStreamRecvError;
use tokio_stream::wrappers::BroadcastStream;

/// The header a POST carries the token in.
pub const TOKEN_HEADER: &str = "x-gonio-token";

static PAGE: &str = include_str!("page.html");

/// Serves a new live scan's page at `addr` (this machine only), and says
/// where when `announce`d: every scan serves it, so that `gonio pause DIR`
/// reaches the scan from another terminal.
pub async fn start(addr: SocketAddr, announce: bool, operator: Operator) -> Result<Live> {
    if !addr.ip().is_loopback() {
        bail!("--live-addr {addr}: the live page pauses and aborts the scan; it listens on this machine only (127.0.0.1 or [::1])");
    }
    let live = Live::default();
    let served = serve(live.clone(), addr).await?;
    if announce {
        operator.notice(format_args!("live view: {}", served.url));
    }
    Ok(live.served_at(served))
}

/// Serves `live` at `addr` (port 0: any free one) on the current runtime,
/// under a new token; returns where.
pub async fn serve(live: Live, addr: SocketAddr) -> Result<Served> {
    let listener = tokio::net::TcpListener::bind(addr)
        .await
        .with_context(|| format!("the live view cannot listen on {addr}"))?;
    let authority = listener.local_addr().context("the live view's address")?.to_string();
    let token = format!("{:032x}", rand::random::<u128>());
    let served = Served {
        url: format!("http://{authority}/?token={token}"),
        origin: format!("http://{authority}"),
        token,
    };
    let gate = Arc::new(served.clone());
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
        .with_state(live)
        .layer(middleware::from_fn_with_state(gate, admit));
    tokio::spawn(async move {
        // The server ends with the process; an error here (the socket
        // failing) leaves the scan running without its page.
        let _ = axum::serve(listener, app).await;
    });
    Ok(served)
}

/// Why a request is refused, or `None` to answer it (see the module's doc).
fn admitted(gate: &Served, method: &Method, headers: &header::HeaderMap, query: Option<&str>) -> Option<(StatusCode, String)> {
    let text = |name: &str| headers.get(name).and_then(|v| v.to_str().ok());
    let forbidden = |why: String| Some((StatusCode::FORBIDDEN, why));
    // `127.0.0.1:PORT`, as printed.
    let authority = gate.origin.strip_prefix("http://");
    if text(header::HOST.as_str()) != authority {
        return forbidden(format!("this live view answers at {} only", gate.origin));
    }
    let from_header = text(TOKEN_HEADER);
    let from_query = query.and_then(|q| q.split('&').find_map(|kv| kv.strip_prefix("token=")));
    let post = method == Method::POST;
    let given = if post { from_header } else { from_header.or(from_query) };
    if !given.is_some_and(|t| same(t.as_bytes(), gate.token.as_bytes())) {
        return forbidden("the scan's token is missing or wrong: open the address the scan printed (or DIR/live.json's)".into());
    }
    if post {
        if text(header::ORIGIN.as_str()).is_some_and(|o| o != gate.origin) {
            return forbidden(format!("requests come from {} only", gate.origin));
        }
        if !text(header::CONTENT_TYPE.as_str()).is_some_and(|c| c.starts_with("application/json")) {
            return Some((StatusCode::UNSUPPORTED_MEDIA_TYPE, "a request's body is JSON".into()));
        }
    }
    None
}

/// Equal, in a time that does not say how much of `a` matched.
fn same(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

async fn admit(State(gate): State<Arc<Served>>, req: Request, next: Next) -> Response {
    match admitted(&gate, req.method(), req.headers(), req.uri().query()) {
        None => next.run(req).await,
        Some((status, why)) => (status, Json(serde_json::json!({ "error": why }))).into_response(),
    }
}

fn accepted(live: &Live) -> impl IntoResponse {
    Json(serde_json::json!({ "accepted": true, "state": live.current_state() }))
}

async fn state(State(live): State<Live>) -> impl IntoResponse {
    Json(live.subscribe().0)
}

async fn events(State(live): State<Live>) -> Sse<impl Stream<Item = Result<Event, Infallible>>> {
    let (seen, rx) = live.subscribe();
    let snapshot = |seen: &super::live::Seen| Event::default().event("snapshot").json_data(seen).unwrap_or_default();
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

#[cfg(test)]
mod tests {
    use super::*;
    use axum::http::HeaderValue;

    fn gate() -> Served {
        Served {
            url: "http://127.0.0.1:4000/?token=0123456789abcdef".into(),
            origin: "http://127.0.0.1:4000".into(),
            token: "0123456789abcdef".into(),
        }
    }

    fn headers(pairs: &[(&'static str, &'static str)]) -> header::HeaderMap {
        let mut h = header::HeaderMap::new();
        for (k, v) in pairs {
            h.insert(*k, HeaderValue::from_static(v));
        }
        h
    }

    #[test]
    fn only_the_printed_address_with_the_token_is_answered() {
        let g = gate();
        let ok = headers(&[("host", "127.0.0.1:4000")]);
        assert_eq!(admitted(&g, &Method::GET, &ok, Some("token=0123456789abcdef")), None);
        // A rebound name, no token, a wrong one, a prefix of it.
        let rebound = headers(&[("host", "evil.example:4000")]);
        let refused = |h: &header::HeaderMap, q: Option<&str>| admitted(&g, &Method::GET, h, q).unwrap().0;
        assert_eq!(refused(&rebound, Some("token=0123456789abcdef")), StatusCode::FORBIDDEN);
        assert_eq!(refused(&ok, None), StatusCode::FORBIDDEN);
        assert_eq!(refused(&ok, Some("token=0123456789abcdee")), StatusCode::FORBIDDEN);
        assert_eq!(refused(&ok, Some("token=0123")), StatusCode::FORBIDDEN);
    }

    #[test]
    fn a_post_needs_the_token_in_a_header_its_own_origin_and_json() {
        let g = gate();
        let post = |pairs: &[(&'static str, &'static str)], q: Option<&str>| admitted(&g, &Method::POST, &headers(pairs), q);
        let page = [
            ("host", "127.0.0.1:4000"),
            ("origin", "http://127.0.0.1:4000"),
            ("content-type", "application/json"),
            ("x-gonio-token", "0123456789abcdef"),
        ];
        assert_eq!(post(&page, None), None);
        // `gonio pause DIR` sends no Origin.
        assert_eq!(post(&[page[0], page[2], page[3]], None), None);
        // Another origin; a form's body; the token in the query only.
        let other = [page[0], ("origin", "http://127.0.0.1:8000"), page[2], page[3]];
        assert_eq!(post(&other, None).unwrap().0, StatusCode::FORBIDDEN);
        let form = [page[0], page[1], ("content-type", "text/plain"), page[3]];
        assert_eq!(post(&form, None).unwrap().0, StatusCode::UNSUPPORTED_MEDIA_TYPE);
        assert_eq!(
            post(&[page[0], page[1], page[2]], Some("token=0123456789abcdef")).unwrap().0,
            StatusCode::FORBIDDEN
        );
    }
}
