//! HTTP/1.1 on a `TcpStream`, as little of it as a local page and scripts need: one request per
//! connection (`Connection: close`), a body only with `Content-Length`. The request head is
//! parsed by `httparse` (hyper's parser); this module bounds what a client can make the server
//! read or wait for, and writes the answer.
//!
//! It is not `tiny_http` any more because the server must see a client go away while its job
//! runs (the job is then cancelled): that needs the socket, which `tiny_http` keeps to itself.

use std::io::{self, Read, Write};
use std::net::TcpStream;
use std::time::Duration;

use crate::limits;
use crate::routes::Reply;

/// Largest request head (request line and headers) [bytes].
pub const MAX_HEAD: usize = 16 * 1024;
/// How long a client may take to send its request, and the server to send its answer.
pub const IO_TIMEOUT: Duration = Duration::from_secs(10);

/// A request as read from a connection.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    pub method: String,
    pub url: String,
    pub body: Vec<u8>,
}

/// Reads one request from `stream`: the answer to send at once instead (a malformed request, a
/// body over [`limits::MAX_BODY`], refused before it is read), or `Err` when the client went
/// away or was too slow (nothing to answer).
pub fn read_request(stream: &mut TcpStream) -> io::Result<Result<Request, Reply>> {
    stream.set_read_timeout(Some(IO_TIMEOUT))?;
    stream.set_write_timeout(Some(IO_TIMEOUT))?;
    let mut buf = Vec::with_capacity(1024);
    let mut chunk = [0u8; 4096];
    let head_len = loop {
        if let Some(end) = find_head_end(&buf) {
            break end;
        }
        if buf.len() > MAX_HEAD {
            return Ok(Err(Reply::error(
                431,
                format!("request head: over this server's limit of {MAX_HEAD} bytes"),
            )));
        }
        let n = stream.read(&mut chunk)?;
        if n == 0 {
            return Err(io::ErrorKind::UnexpectedEof.into());
        }
        buf.extend_from_slice(&chunk[..n]);
    };
    let mut headers = [httparse::EMPTY_HEADER; 64];
    let mut parsed = httparse::Request::new(&mut headers);
    match parsed.parse(&buf[..head_len]) {
        Ok(httparse::Status::Complete(_)) => {}
        Ok(httparse::Status::Partial) | Err(_) => {
            return Ok(Err(Reply::error(400, "request: not HTTP/1.1".into())));
        }
    }
    let method = parsed.method.unwrap_or("").to_string();
    let url = parsed.path.unwrap_or("").to_string();
    let header = |name: &str| {
        parsed
            .headers
            .iter()
            .find(|h| h.name.eq_ignore_ascii_case(name))
            .map(|h| String::from_utf8_lossy(h.value).trim().to_string())
    };
    if header("transfer-encoding").is_some() {
        return Ok(Err(Reply::error(
            411,
            "request body: send it with Content-Length (no Transfer-Encoding)".into(),
        )));
    }
    let length = match header("content-length") {
        None => 0,
        Some(text) => match text.parse::<usize>() {
            Ok(n) => n,
            Err(_) => {
                return Ok(Err(Reply::error(
                    400,
                    format!("Content-Length: `{text}` is not a number of bytes"),
                )))
            }
        },
    };
    if length > limits::MAX_BODY {
        return Ok(Err(Reply::too_large_body(length)));
    }
    if header("expect").is_some_and(|e| e.eq_ignore_ascii_case("100-continue")) {
        stream.write_all(b"HTTP/1.1 100 Continue\r\n\r\n")?;
    }
    let mut body = buf[head_len..].to_vec();
    body.truncate(length);
    let mut rest = (length - body.len()) as u64;
    if rest > 0 {
        let read = Read::by_ref(stream).take(rest).read_to_end(&mut body)?;
        rest -= read as u64;
    }
    if rest > 0 {
        return Err(io::ErrorKind::UnexpectedEof.into());
    }
    Ok(Ok(Request { method, url, body }))
}

/// Where the head ends (just after the blank line), if it has.
fn find_head_end(buf: &[u8]) -> Option<usize> {
    buf.windows(4).position(|w| w == b"\r\n\r\n").map(|i| i + 4)
}

/// The reason phrase of the statuses the server sends.
fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        400 => "Bad Request",
        404 => "Not Found",
        405 => "Method Not Allowed",
        411 => "Length Required",
        413 => "Content Too Large",
        422 => "Unprocessable Content",
        431 => "Request Header Fields Too Large",
        500 => "Internal Server Error",
        503 => "Service Unavailable",
        _ => "",
    }
}

/// Writes `reply` (its body left out for a HEAD request) and closes the connection.
pub fn write_reply(stream: &mut TcpStream, reply: &Reply, head_only: bool) -> io::Result<()> {
    let mut out = format!(
        "HTTP/1.1 {} {}\r\nContent-Type: {}\r\nContent-Length: {}\r\nConnection: close\r\n",
        reply.status,
        reason(reply.status),
        reply.content_type,
        reply.body.len()
    );
    if reply.status == 503 {
        out.push_str("Retry-After: 1\r\n");
    }
    out.push_str("\r\n");
    let mut bytes = out.into_bytes();
    if !head_only {
        bytes.extend_from_slice(&reply.body);
    }
    stream.write_all(&bytes)?;
    stream.flush()?;
    let _ = stream.shutdown(std::net::Shutdown::Write);
    Ok(())
}

/// Whether the client closed its side of `stream` (it reads end-of-file without blocking): the
/// answer would go nowhere, so its job may stop. Bytes it sent after its request (a pipelined
/// request, ignored: one request per connection) do not count as leaving.
pub fn client_left(stream: &TcpStream) -> bool {
    if stream.set_nonblocking(true).is_err() {
        return true;
    }
    let mut byte = [0u8; 1];
    let left = match stream.peek(&mut byte) {
        Ok(0) => true,
        Ok(_) => false,
        Err(e) => e.kind() != io::ErrorKind::WouldBlock,
    };
    let _ = stream.set_nonblocking(false);
    left
}
