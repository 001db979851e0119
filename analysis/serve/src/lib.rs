//! `twv serve`: one page whose sliders are the pitch gains, the controller's options and the
//! vehicle's parameters, and whose plots — the tilt recovery, phase portraits, Bode and Nyquist
//! with the margins, the closed-loop poles, a (Kp, Kd) map — redraw as they move. The page
//! talks to a JSON API under `/api/` ([`routes`]) that calls the twv-analysis API; every
//! request is bounded ([`limits`]) so that none can hang the server.
//!
//! Below the CLI nothing parses arguments: [`ServeSettings`] is typed, [`Server::bind`] opens
//! the socket and [`Server::run`] answers until a [`CancelFlag`] is raised.
//!
//! How the work is shared out, so that no client can tie the server up:
//! - one thread accepts connections and hands them to [`READERS`] reader threads through a
//!   queue of [`CONNECTION_QUEUE`] (a connection beyond it is answered 503 at once);
//! - a reader reads the request within [`http::IO_TIMEOUT`] and answers everything cheap itself
//!   (the page's files, `GET /api/model`, errors), so these answer while jobs run;
//! - a job (`POST /api/<job>`) goes to a queue of [`ServeSettings::queue`] for the
//!   [`ServeSettings::workers`] job threads, 503 when it is full;
//! - a running job is cancelled (the library's cancellation, at its next chunk of work) when its
//!   client goes away, when it runs past [`ServeSettings::time_limit`] (answered 413), or when
//!   the server stops.

pub mod assets;
pub mod http;
pub mod limits;
pub mod routes;

use std::net::{IpAddr, Ipv4Addr, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{sync_channel, Receiver, RecvTimeoutError, SyncSender, TrySendError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use twv_analysis::api::Progress;
use twv_analysis::model::ResolvedModel;

pub use routes::{respond, respond_with, Reply, State};
pub use twv_analysis::api::CancelFlag;

/// Threads reading requests and answering the cheap ones.
pub const READERS: usize = 8;
/// Connections waiting for a reader before new ones are answered 503.
pub const CONNECTION_QUEUE: usize = 64;
/// How often waiting threads look at the stop flag, and a running job at its client.
const POLL: Duration = Duration::from_millis(50);

/// Where and how to serve.
#[derive(Debug, Clone, PartialEq)]
pub struct ServeSettings {
    /// Address to bind. Default 127.0.0.1: only this machine can reach the page.
    pub bind: IpAddr,
    /// Port; 0 picks a free one (printed by [`Server::url`]). Default 8040.
    pub port: u16,
    /// Threads running jobs. Default 2 (this machine's cores).
    pub workers: usize,
    /// Jobs that may wait for a job thread; one more is answered 503. Default 8.
    pub queue: usize,
    /// How long one job may run before it is cancelled and answered 413. Default 10 s.
    pub time_limit: Duration,
}

impl Default for ServeSettings {
    fn default() -> Self {
        Self {
            bind: IpAddr::V4(Ipv4Addr::LOCALHOST),
            port: 8040,
            workers: 2,
            queue: 8,
            time_limit: Duration::from_secs(10),
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
    /// Bad settings.
    #[error("queue: {0} must be between 1 and 1024")]
    Queue(usize),
    /// Bad settings.
    #[error("time_limit: {0:?} must be between 1 ms and 1 hour")]
    TimeLimit(Duration),
}

/// A bound server: the page and the API for one model.
pub struct Server {
    listener: TcpListener,
    state: Arc<State>,
    settings: ServeSettings,
}

/// A job request waiting for a job thread, with its client's connection.
struct Ticket {
    request: http::Request,
    stream: TcpStream,
}

/// Why a running job was asked to stop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stop {
    ClientLeft,
    TimeLimit,
    Shutdown,
}

/// A running job's [`Progress`]: cancelled when the server stops, the time limit passes or the
/// client closes its connection (looked at no more often than every [`POLL`]).
struct Watch<'a> {
    stop: &'a CancelFlag,
    stream: &'a TcpStream,
    started: Instant,
    limit: Duration,
    /// Nanoseconds after `started` of the last look at the client.
    looked: AtomicU64,
    left: AtomicBool,
}

impl Watch<'_> {
    fn why(&self) -> Option<Stop> {
        if self.stop.is_raised() {
            return Some(Stop::Shutdown);
        }
        let now = self.started.elapsed();
        if now > self.limit {
            return Some(Stop::TimeLimit);
        }
        let nanos = now.as_nanos() as u64;
        let last = self.looked.load(Ordering::Relaxed);
        if nanos.saturating_sub(last) >= POLL.as_nanos() as u64
            && self
                .looked
                .compare_exchange(last, nanos, Ordering::Relaxed, Ordering::Relaxed)
                .is_ok()
            && http::client_left(self.stream)
        {
            self.left.store(true, Ordering::Relaxed);
        }
        self.left
            .load(Ordering::Relaxed)
            .then_some(Stop::ClientLeft)
    }
}

impl Progress for Watch<'_> {
    fn cancelled(&self) -> bool {
        self.why().is_some()
    }
}

/// Takes the next item of a queue shared by several threads, waiting at most [`POLL`].
fn next<T>(queue: &Mutex<Receiver<T>>) -> Result<T, RecvTimeoutError> {
    match queue.lock() {
        Ok(rx) => rx.recv_timeout(POLL),
        Err(_) => Err(RecvTimeoutError::Disconnected),
    }
}

impl Server {
    /// Binds the socket for `model`.
    pub fn bind(model: ResolvedModel, settings: &ServeSettings) -> Result<Self, ServeError> {
        if !(1..=64).contains(&settings.workers) {
            return Err(ServeError::Workers(settings.workers));
        }
        if !(1..=1024).contains(&settings.queue) {
            return Err(ServeError::Queue(settings.queue));
        }
        if !(Duration::from_millis(1)..=Duration::from_secs(3600)).contains(&settings.time_limit) {
            return Err(ServeError::TimeLimit(settings.time_limit));
        }
        let addr = SocketAddr::new(settings.bind, settings.port);
        let listener = TcpListener::bind(addr).map_err(|e| ServeError::Bind {
            addr,
            reason: e.to_string(),
        })?;
        Ok(Self {
            listener,
            state: Arc::new(State::new(model)),
            settings: settings.clone(),
        })
    }

    /// The address actually bound (the port chosen when 0 was asked for).
    pub fn addr(&self) -> SocketAddr {
        self.listener
            .local_addr()
            .expect("a bound listener has an address")
    }

    /// The page's address.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr())
    }

    /// Answers requests until `stop` is raised; returns within a fraction of a second of it
    /// (a running job is cancelled at its next chunk of work).
    pub fn run(&self, stop: &CancelFlag) {
        let (connections, waiting) = sync_channel::<TcpStream>(CONNECTION_QUEUE);
        let (jobs, queued) = sync_channel::<Ticket>(self.settings.queue);
        let (waiting, queued) = (Mutex::new(waiting), Mutex::new(queued));
        if self.listener.set_nonblocking(true).is_err() {
            return;
        }
        std::thread::scope(|scope| {
            for _ in 0..READERS {
                scope.spawn(|| {
                    while !stop.is_raised() {
                        match next(&waiting) {
                            Ok(stream) => self.read(stream, &jobs),
                            Err(RecvTimeoutError::Timeout) => {}
                            Err(RecvTimeoutError::Disconnected) => break,
                        }
                    }
                });
            }
            for _ in 0..self.settings.workers {
                scope.spawn(|| {
                    while !stop.is_raised() {
                        match next(&queued) {
                            Ok(ticket) => self.work(ticket, stop),
                            Err(RecvTimeoutError::Timeout) => {}
                            Err(RecvTimeoutError::Disconnected) => break,
                        }
                    }
                });
            }
            while !stop.is_raised() {
                match self.listener.accept() {
                    Ok((stream, _)) => {
                        let _ = stream.set_nonblocking(false);
                        if let Err(TrySendError::Full(mut stream)) = connections.try_send(stream) {
                            let busy = Reply::error(
                                503,
                                format!(
                                    "busy: {CONNECTION_QUEUE} connections are waiting; try again"
                                ),
                            );
                            let _ = stream.set_write_timeout(Some(http::IO_TIMEOUT));
                            let _ = http::write_reply(&mut stream, &busy, false);
                        }
                    }
                    Err(_) => std::thread::sleep(POLL / 5),
                }
            }
        });
    }

    /// Reads a request and answers it, or queues it for a job thread.
    fn read(&self, mut stream: TcpStream, jobs: &SyncSender<Ticket>) {
        let request = match http::read_request(&mut stream) {
            Err(_) => return,
            Ok(Err(reply)) => {
                let _ = http::write_reply(&mut stream, &reply, false);
                return;
            }
            Ok(Ok(request)) => request,
        };
        if !routes::is_job(&request.method, &request.url) {
            let reply = guarded(&self.state, &request, &twv_analysis::api::Silent);
            let _ = http::write_reply(&mut stream, &reply, request.method == "HEAD");
            return;
        }
        let refused = match jobs.try_send(Ticket { request, stream }) {
            Ok(()) => return,
            Err(TrySendError::Full(t)) => (
                t,
                format!(
                    "busy: {} jobs are waiting for this server's {} job threads; try again",
                    self.settings.queue, self.settings.workers
                ),
            ),
            Err(TrySendError::Disconnected(t)) => (t, "the server is stopping".to_string()),
        };
        let (mut ticket, why) = refused;
        let _ = http::write_reply(&mut ticket.stream, &Reply::error(503, why), false);
    }

    /// Runs a queued job, watched for its client, its time limit and the server's stop.
    fn work(&self, mut ticket: Ticket, stop: &CancelFlag) {
        if http::client_left(&ticket.stream) {
            return;
        }
        let watch = Watch {
            stop,
            stream: &ticket.stream,
            started: Instant::now(),
            limit: self.settings.time_limit,
            looked: AtomicU64::new(0),
            left: AtomicBool::new(false),
        };
        let reply = guarded(&self.state, &ticket.request, &watch);
        let reply = match (reply.status, watch.why()) {
            (_, Some(Stop::ClientLeft)) => return,
            (503, Some(Stop::TimeLimit)) => Reply::error(
                413,
                format!(
                    "the job ran past this server's time limit of {} s and was stopped (ask \
                     for less work: fewer points, a shorter run, fewer iterations)",
                    self.settings.time_limit.as_secs_f64()
                ),
            ),
            (503, Some(Stop::Shutdown)) => {
                Reply::error(503, "the server is stopping; the job was cancelled".into())
            }
            _ => reply,
        };
        let _ = http::write_reply(&mut ticket.stream, &reply, false);
    }
}

/// [`respond_with`], a panic of a job costing that request (a 500 with the reason), not the
/// thread: the server keeps answering.
fn guarded(state: &State, request: &http::Request, progress: &dyn Progress) -> Reply {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        respond_with(
            state,
            &request.method,
            &request.url,
            &request.body,
            progress,
        )
    }))
    .unwrap_or_else(|panic| {
        let reason = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown".into());
        Reply::error(500, format!("internal error (a defect of twv): {reason}"))
    })
}
