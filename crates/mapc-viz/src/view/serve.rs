//! `mapc view --serve`: the page over HTTP on the loopback interface, for runs too large to inline. Two
//! resources, `/` (the page without data) and `/data.json`; every other path is 404. One connection at a time is
//! plenty for one person's browser. The page goes out with its Content-Security-Policy as a header too (the same
//! as its `<meta>`: [`super::content_security_policy`] for [`super::Delivery::Served`]), and no answer may be
//! sniffed as another type than it says.

use std::io::{BufRead, BufReader, Write};
use std::net::{TcpListener, TcpStream};

/// Answer requests on `listener` until `max_requests` have been served (`None`: forever). The caller binds the
/// listener (to 127.0.0.1) and prints its address. `page` is [`super::page_without_data`]'s, whose `<meta>` policy is
/// the header sent with it.
pub fn serve(
    listener: &TcpListener,
    page: &str,
    data_json: &str,
    max_requests: Option<usize>,
) -> std::io::Result<()> {
    let page_policy = super::content_security_policy(super::Delivery::Served);
    for (served, stream) in listener.incoming().enumerate() {
        // a client that hangs up early is its own business; the server goes on
        if let Ok(stream) = stream {
            let _ = answer(stream, page, &page_policy, data_json);
        }
        if max_requests.is_some_and(|m| served + 1 >= m) {
            break;
        }
    }
    Ok(())
}

fn answer(
    stream: TcpStream,
    page: &str,
    page_policy: &str,
    data_json: &str,
) -> std::io::Result<()> {
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
    // what is not the page runs nothing, should a browser open it
    let nothing = "default-src 'none'";
    let (code, kind, body, policy) = match (method, path) {
        ("GET" | "HEAD", "/" | "/index.html") => {
            ("200 OK", "text/html; charset=utf-8", page, page_policy)
        }
        ("GET" | "HEAD", "/data.json") => ("200 OK", "application/json", data_json, nothing),
        ("GET" | "HEAD", _) => (
            "404 Not Found",
            "text/plain; charset=utf-8",
            "not found\n",
            nothing,
        ),
        _ => (
            "405 Method Not Allowed",
            "text/plain; charset=utf-8",
            "only GET\n",
            nothing,
        ),
    };
    let mut out = stream;
    write!(
        out,
        "HTTP/1.1 {code}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nContent-Security-Policy: {policy}\r\n\
         X-Content-Type-Options: nosniff\r\nReferrer-Policy: no-referrer\r\nCache-Control: no-store\r\n\
         Connection: close\r\n\r\n",
        body.len()
    )?;
    if method != "HEAD" {
        out.write_all(body.as_bytes())?;
    }
    out.flush()
}
