//! A minimal blocking HTTP/1.1 client for the studio's endpoints, for
//! tests, benchmarks and scripts: one connection per request, no TLS, no
//! redirects.

use serde_json::Value;
use std::io::{BufRead, BufReader, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::Duration;

/// A reply: status, headers (lower-case names) and body.
#[derive(Debug)]
pub struct Reply {
    /// HTTP status code.
    pub status: u16,
    /// Header (lower-case name, value) pairs.
    pub headers: Vec<(String, String)>,
    /// The body.
    pub body: Vec<u8>,
}

impl Reply {
    /// The body as JSON (`Value::Null` if it is not JSON).
    pub fn json(&self) -> Value {
        serde_json::from_slice(&self.body).unwrap_or(Value::Null)
    }
    /// A header's value.
    pub fn header(&self, name: &str) -> Option<&str> {
        let n = name.to_ascii_lowercase();
        self.headers
            .iter()
            .find(|(k, _)| *k == n)
            .map(|(_, v)| v.as_str())
    }
}

/// Talks to a studio at one address.
#[derive(Clone, Debug)]
pub struct Client {
    addr: SocketAddr,
    /// Host header sent (default `127.0.0.1:PORT`).
    pub host: String,
    /// Read timeout per request.
    pub timeout: Duration,
    /// The studio's token, sent as `X-Studio-Token` when set.
    pub token: Option<String>,
}

impl Client {
    /// A client for the server at `addr`.
    pub fn new(addr: SocketAddr) -> Client {
        Client {
            addr,
            host: format!("127.0.0.1:{}", addr.port()),
            timeout: Duration::from_secs(120),
            token: None,
        }
    }

    /// The same client, sending `token` with every request.
    pub fn with_token(mut self, token: &str) -> Client {
        self.token = Some(token.to_string());
        self
    }

    /// Sends a request; `body` with `Content-Type: application/json` when
    /// given. `POST`s carry `X-Studio: 1`, every request the token if set.
    pub fn request(
        &self,
        method: &str,
        path: &str,
        body: Option<&[u8]>,
        extra: &[(&str, &str)],
    ) -> std::io::Result<Reply> {
        let mut s = TcpStream::connect(self.addr)?;
        s.set_read_timeout(Some(self.timeout))?;
        let mut head = format!(
            "{method} {path} HTTP/1.1\r\nHost: {}\r\nConnection: close\r\n",
            self.host
        );
        if method == "POST" {
            head += "X-Studio: 1\r\n";
        }
        if let Some(t) = &self.token {
            head += &format!("X-Studio-Token: {t}\r\n");
        }
        for (k, v) in extra {
            head += &format!("{k}: {v}\r\n");
        }
        let body = body.unwrap_or(&[]);
        if method == "POST" || !body.is_empty() {
            head += &format!(
                "Content-Type: application/json\r\nContent-Length: {}\r\n",
                body.len()
            );
        }
        head += "\r\n";
        s.write_all(head.as_bytes())?;
        s.write_all(body)?;
        s.flush()?;
        read_reply(BufReader::new(s))
    }

    /// `GET path`.
    pub fn get(&self, path: &str) -> std::io::Result<Reply> {
        self.request("GET", path, None, &[])
    }

    /// `POST path` with a JSON body; the reply's JSON, or an error for a
    /// status other than 200.
    pub fn post_json(&self, path: &str, v: &Value) -> std::io::Result<Value> {
        let r = self.request("POST", path, Some(v.to_string().as_bytes()), &[])?;
        if r.status != 200 {
            return Err(std::io::Error::other(format!(
                "POST {path}: status {}: {}",
                r.status,
                String::from_utf8_lossy(&r.body)
            )));
        }
        Ok(r.json())
    }

    /// `GET path`; the reply's JSON, or an error for a status other than 200.
    pub fn get_json(&self, path: &str) -> std::io::Result<Value> {
        let r = self.get(path)?;
        if r.status != 200 {
            return Err(std::io::Error::other(format!(
                "GET {path}: status {}: {}",
                r.status,
                String::from_utf8_lossy(&r.body)
            )));
        }
        Ok(r.json())
    }
}

fn read_reply(mut r: impl BufRead) -> std::io::Result<Reply> {
    let bad = |m: &str| std::io::Error::new(std::io::ErrorKind::InvalidData, m.to_string());
    let mut line = String::new();
    r.read_line(&mut line)?;
    let status: u16 = line
        .split_whitespace()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| bad("bad status line"))?;
    let mut headers = Vec::new();
    loop {
        line.clear();
        r.read_line(&mut line)?;
        let l = line.trim_end();
        if l.is_empty() {
            break;
        }
        if let Some((k, v)) = l.split_once(':') {
            headers.push((k.trim().to_ascii_lowercase(), v.trim().to_string()));
        }
    }
    let find = |n: &str| headers.iter().find(|(k, _)| k == n).map(|(_, v)| v.clone());
    let mut body = Vec::new();
    if find("transfer-encoding").is_some_and(|v| v.eq_ignore_ascii_case("chunked")) {
        loop {
            line.clear();
            r.read_line(&mut line)?;
            let n = usize::from_str_radix(line.trim().split(';').next().unwrap_or(""), 16)
                .map_err(|_| bad("bad chunk size"))?;
            if n == 0 {
                break;
            }
            let start = body.len();
            body.resize(start + n, 0);
            r.read_exact(&mut body[start..])?;
            line.clear();
            r.read_line(&mut line)?;
        }
    } else if let Some(n) = find("content-length") {
        let n: usize = n.parse().map_err(|_| bad("bad content-length"))?;
        body.resize(n, 0);
        r.read_exact(&mut body)?;
    } else {
        r.read_to_end(&mut body)?;
    }
    Ok(Reply {
        status,
        headers,
        body,
    })
}
