//! `twv serve`: one page whose sliders are the pitch gains, the controller's options and the
//! vehicle's parameters, and whose plots — the tilt recovery, phase portraits, Bode and Nyquist
//! with the margins, the closed-loop poles, a (Kp, Kd) map — redraw as they move. The page
//! talks to a JSON API under `/api/` ([`routes`]) that calls the twv-analysis API; every
//! request is bounded ([`limits`]) so that none can hang the server.
//!
//! Below the CLI nothing parses arguments: [`ServeSettings`] is typed, [`Server::bind`] opens
//! the socket and [`Server::run`] answers until a [`CancelFlag`] is raised.

pub mod assets;
pub mod limits;
pub mod routes;

use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::sync::Arc;
use std::time::Duration;

use twv_analysis::model::ResolvedModel;

pub use routes::{respond, Reply, State};
pub use twv_analysis::api::CancelFlag;

/// Where and how to serve.
#[derive(Debug, Clone, PartialEq)]
pub struct ServeSettings {
    /// Address to bind. Default 127.0.0.1: only this machine can reach the page.
    pub bind: IpAddr,
    /// Port; 0 picks a free one (printed by [`Server::url`]). Default 8040.
    pub port: u16,
    /// Threads answering requests. Default 2 (this machine's cores).
    pub workers: usize,
}

impl Default for ServeSettings {
    fn default() -> Self {
        Self {
            bind: IpAddr::V4(Ipv4Addr::LOCALHOST),
            port: 8040,
            workers: 2,
        }
    }
}

/// Why the server could not start.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// The address could not be bound (in use, not permitted, not an address of this machine).
    #[error("cannot listen on {addr}: {reason}")]
    Bind { addr: SocketAddr, reason: String },
    /// Bad settings.
    #[error("workers: {0} must be between 1 and 64")]
    Workers(usize),
}

/// A bound server: the page and the API for one model.
pub struct Server {
    http: Arc<tiny_http::Server>,
    state: Arc<State>,
    workers: usize,
}

impl Server {
    /// Binds the socket for `model`.
    pub fn bind(model: ResolvedModel, settings: &ServeSettings) -> Result<Self, ServeError> {
        if !(1..=64).contains(&settings.workers) {
            return Err(ServeError::Workers(settings.workers));
        }
        let addr = SocketAddr::new(settings.bind, settings.port);
        let http = tiny_http::Server::http(addr).map_err(|e| ServeError::Bind {
            addr,
            reason: e.to_string(),
        })?;
        Ok(Self {
            http: Arc::new(http),
            state: Arc::new(State::new(model)),
            workers: settings.workers,
        })
    }

    /// The address actually bound (the port chosen when 0 was asked for).
    pub fn addr(&self) -> SocketAddr {
        self.http
            .server_addr()
            .to_ip()
            .expect("bound to an IP address")
    }

    /// The page's address.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr())
    }

    /// Answers requests on the worker threads until `stop` is raised (checked every 100 ms).
    pub fn run(&self, stop: &CancelFlag) {
        std::thread::scope(|scope| {
            for _ in 0..self.workers {
                scope.spawn(|| {
                    while !stop.is_raised() {
                        match self.http.recv_timeout(Duration::from_millis(100)) {
                            Ok(Some(request)) => answer(&self.state, request),
                            Ok(None) => {}
                            Err(_) => break,
                        }
                    }
                });
            }
        });
    }
}

/// Reads at most [`limits::MAX_BODY`] bytes of the body (a longer one is refused unread, so a
/// huge upload costs nothing), answers, and sends the reply; a client that went away is not an
/// error of the server.
fn answer(state: &State, mut request: tiny_http::Request) {
    use std::io::Read;
    let method = request.method().as_str().to_string();
    let url = request.url().to_string();
    let declared = request.body_length().unwrap_or(0);
    let reply = if declared > limits::MAX_BODY {
        Reply::too_large_body(declared)
    } else {
        let mut body = Vec::new();
        let read = request
            .as_reader()
            .take(limits::MAX_BODY as u64 + 1)
            .read_to_end(&mut body);
        match read {
            Err(e) => Reply::error(400, format!("request body: {e}")),
            Ok(n) if n > limits::MAX_BODY => Reply::too_large_body(n),
            // A defect in a job must cost that request (a 500 with the reason), not the
            // worker thread: the server keeps answering.
            Ok(_) => std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                respond(state, &method, &url, &body)
            }))
            .unwrap_or_else(|panic| {
                let reason = panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "unknown".into());
                Reply::error(500, format!("internal error (a defect of twv): {reason}"))
            }),
        }
    };
    let header =
        tiny_http::Header::from_bytes("Content-Type", reply.content_type).expect("a valid header");
    let response = tiny_http::Response::from_data(reply.body)
        .with_status_code(reply.status)
        .with_header(header);
    let _ = request.respond(response);
}
