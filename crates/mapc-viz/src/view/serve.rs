//! `mapc view --serve`: the page over HTTP on the loopback interface, for runs too large to inline. Two
//! resources, `/` (the page without data) and `/data.json`; every other path is 404. One connection at a time is
//! plenty for one person's browser.

use std::io::{BufRead, BufReader, Write};
use std::net::{TcpListener, TcpStream};

/// Answer requests on `listener` until `max_requests` have been served (`None`: forever). The caller binds the
/// listener (to 127.0.0.1) and prints its address.
pub fn serve(
    listener: &TcpListener,
    page: &str,
    data_json: &str,
    max_requests: Option<usize>,
) -> std::io::Result<()> {
    for (served, stream) in listener.incoming().enumerate() {
        // a client that hangs up early is its own business; the server goes on
        if let Ok(stream) = stream {
            let _ = answer(stream, page, data_json);
        }
        if max_requests.is_some_and(|m| served + 1 >= m) {
            break;
        }
    }
    Ok(())
}

fn answer(stream: TcpStream, page: &str, data_json: &str) -> std::io::Result<()> {
    stream.set_read_timeout(Some(std::time::Duration::from_secs(10)))?;
    let mut reader = BufReader::new(stream.try_clone()?);
    let mut request = String::new();
    reader.read_line(&mut request)?;
    // the headers are read and ignored: nothing in them changes the answer
    let mut line = String::new();
    while reader.read_line(&mut line)? > 2 {
        line.clear();
    }
    let mut words = request.split_whitespace();
    let (method, target) = (words.next().unwrap_or(""), words.next().unwrap_or(""));
    let path = target.split(['?', '#']).next().unwrap_or("");
    let (code, kind, body) = match (method, path) {
        ("GET" | "HEAD", "/" | "/index.html") => ("200 OK", "text/html; charset=utf-8", page),
        ("GET" | "HEAD", "/data.json") => ("200 OK", "application/json", data_json),
        ("GET" | "HEAD", _) => ("404 Not Found", "text/plain; charset=utf-8", "not found\n"),
        _ => (
            "405 Method Not Allowed",
            "text/plain; charset=utf-8",
            "only GET\n",
        ),
    };
    let mut out = stream;
    write!(
        out,
        "HTTP/1.1 {code}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n",
        body.len()
    )?;
    if method != "HEAD" {
        out.write_all(body.as_bytes())?;
    }
    out.flush()
}
