//! The little HTTP/1.1 that `sdfc serve` speaks: one request per connection (every
//! response closes it), GET and HEAD only, a bounded request head, and request paths
//! percent-decoded once into plain components that can only name something below the
//! site's root.

use std::io::{Read, Write};

/// The largest request head (request line and headers) read, in bytes.
pub const MAX_HEAD_BYTES: usize = 8 << 10;

/// A request's method and decoded path.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Request {
    /// Whether it is HEAD (the headers of GET, no body).
    pub head: bool,
    /// The path's components below the root, percent-decoded; empty for `/`.
    pub path: Vec<String>,
    /// The `Host` header, if any.
    pub host: Option<String>,
}

/// Why a request is answered with an error.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Refused {
    /// Malformed: 400.
    Bad,
    /// A method other than GET or HEAD: 405.
    Method,
    /// The head is over [`MAX_HEAD_BYTES`]: 431.
    TooLarge,
    /// A path that cannot name a file below the root (`..`, `.`, a hidden name, an
    /// empty component, an encoded `/`, NUL or invalid UTF-8): 404, the same answer as a
    /// missing file.
    Path,
    /// The connection ended or timed out before a whole head came: no answer.
    Gone,
}

/// Reads one request head from `stream` (at most [`MAX_HEAD_BYTES`]).
pub fn read_request(stream: &mut impl Read) -> Result<Request, Refused> {
    let mut head = Vec::new();
    let mut buf = [0u8; 1024];
    loop {
        let n = stream.read(&mut buf).map_err(|_| Refused::Gone)?;
        if n == 0 {
            return Err(Refused::Gone);
        }
        head.extend_from_slice(&buf[..n]);
        if let Some(end) = find(&head, b"\r\n\r\n") {
            head.truncate(end);
            break;
        }
        if head.len() > MAX_HEAD_BYTES {
            return Err(Refused::TooLarge);
        }
    }
    if head.len() > MAX_HEAD_BYTES {
        return Err(Refused::TooLarge);
    }
    let text = std::str::from_utf8(&head).map_err(|_| Refused::Bad)?;
    let mut lines = text.split("\r\n");
    let line = lines.next().ok_or(Refused::Bad)?;
    let mut parts = line.split(' ');
    let (Some(method), Some(target), Some(version), None) =
        (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return Err(Refused::Bad);
    };
    if !version.starts_with("HTTP/1.") {
        return Err(Refused::Bad);
    }
    let head = match method {
        "GET" => false,
        "HEAD" => true,
        _ => return Err(Refused::Method),
    };
    let host = lines
        .filter_map(|l| l.split_once(':'))
        .find(|(name, _)| name.eq_ignore_ascii_case("host"))
        .map(|(_, value)| value.trim().to_string());
    Ok(Request {
        head,
        path: decode_path(target)?,
        host,
    })
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// The components of a request target (`/a/b%20c?query`), percent-decoded once. Only
/// an origin-form target (starting with one `/`) is accepted; a component that is
/// empty, `.`, `..`, hidden (starting with `.`), or that holds `/`, `\`, or NUL after
/// decoding is refused, so the result names nothing above the root and no absolute path.
pub fn decode_path(target: &str) -> Result<Vec<String>, Refused> {
    let path = target.split(['?', '#']).next().unwrap_or("");
    let Some(rest) = path.strip_prefix('/') else {
        return Err(Refused::Bad);
    };
    if rest.is_empty() {
        return Ok(Vec::new());
    }
    rest.split('/')
        .map(|raw| {
            let part = percent_decode(raw)?;
            let bad = part.is_empty() || part.starts_with('.') || part.contains(['/', '\\', '\0']);
            if bad {
                Err(Refused::Path)
            } else {
                Ok(part)
            }
        })
        .collect()
}

fn percent_decode(raw: &str) -> Result<String, Refused> {
    let bytes = raw.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = bytes.get(i + 1..i + 3).ok_or(Refused::Bad)?;
            let hex = std::str::from_utf8(hex).map_err(|_| Refused::Bad)?;
            out.push(u8::from_str_radix(hex, 16).map_err(|_| Refused::Bad)?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| Refused::Path)
}

/// The content type of a file by its name.
pub fn content_type(name: &str) -> &'static str {
    let ext = name.rsplit_once('.').map(|(_, e)| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("html") => "text/html; charset=utf-8",
        Some("js" | "mjs") => "text/javascript; charset=utf-8",
        Some("json") => "application/json",
        Some("png") => "image/png",
        Some("jpg" | "jpeg") => "image/jpeg",
        Some("wgsl" | "sdf" | "txt") => "text/plain; charset=utf-8",
        _ => "application/octet-stream",
    }
}

/// Writes a whole response (`Connection: close`); the body is left out for HEAD.
pub fn respond(
    stream: &mut impl Write,
    status: &str,
    kind: &str,
    body: &[u8],
    head: bool,
    extra: &str,
) -> std::io::Result<()> {
    write!(
        stream,
        "HTTP/1.1 {status}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\n\
         Cache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\n{extra}\
         Connection: close\r\n\r\n",
        body.len()
    )?;
    if !head {
        stream.write_all(body)?;
    }
    stream.flush()
}

/// The answer to a refused request, if it gets one.
pub fn refusal(stream: &mut impl Write, why: &Refused) -> std::io::Result<()> {
    let (status, extra) = match why {
        Refused::Bad => ("400 Bad Request", ""),
        Refused::Method => ("405 Method Not Allowed", "Allow: GET, HEAD\r\n"),
        Refused::TooLarge => ("431 Request Header Fields Too Large", ""),
        Refused::Path => return not_found(stream, false),
        Refused::Gone => return Ok(()),
    };
    let body = format!("{status}\n");
    respond(
        stream,
        status,
        "text/plain; charset=utf-8",
        body.as_bytes(),
        false,
        extra,
    )
}

/// 404, the one answer for a missing file and for one that may not be served.
pub fn not_found(stream: &mut impl Write, head: bool) -> std::io::Result<()> {
    respond(
        stream,
        "404 Not Found",
        "text/plain; charset=utf-8",
        b"not found\n",
        head,
        "",
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn req(text: &str) -> Result<Request, Refused> {
        read_request(&mut text.as_bytes())
    }

    #[test]
    fn paths_decode_into_components_below_the_root() {
        assert_eq!(decode_path("/"), Ok(vec![]));
        assert_eq!(
            decode_path("/a/b%20c.png?x=1"),
            Ok(vec!["a".into(), "b c.png".into()])
        );
        for bad in [
            "/../x",
            "/%2e%2e/x",
            "/%2E%2E/x",
            "/a/%2e%2e/%2e%2e/x",
            "/a/..",
            "/./x",
            "//etc/passwd",
            "/%2fetc/passwd",
            "/a%2f..%2fb",
            "/a\\..\\b",
            "/a%5c..%5cb",
            "/a/",
            "/.git/config",
            "/a%00b",
            "/%ff",
        ] {
            assert_eq!(decode_path(bad), Err(Refused::Path), "{bad}");
        }
        for bad in ["http://example.com/x", "x", "/%2", "/%zz", "*"] {
            assert_eq!(decode_path(bad), Err(Refused::Bad), "{bad}");
        }
    }

    #[test]
    fn requests_are_bounded_and_get_or_head_only() {
        let r = req("GET /index.html HTTP/1.1\r\nHost: 127.0.0.1:80\r\n\r\n").unwrap();
        assert_eq!(r.path, vec!["index.html"]);
        assert!(!r.head);
        assert_eq!(r.host.as_deref(), Some("127.0.0.1:80"));
        assert!(req("HEAD / HTTP/1.0\r\n\r\n").unwrap().head);
        assert_eq!(req("POST / HTTP/1.1\r\n\r\n"), Err(Refused::Method));
        assert_eq!(req("DELETE / HTTP/1.1\r\n\r\n"), Err(Refused::Method));
        assert_eq!(req("GET / HTTP/2\r\n\r\n"), Err(Refused::Bad));
        assert_eq!(req("GET  / HTTP/1.1\r\n\r\n"), Err(Refused::Bad));
        assert_eq!(req("GET / HTTP/1.1\r\n"), Err(Refused::Gone));
        let long = format!(
            "GET / HTTP/1.1\r\nX: {}\r\n\r\n",
            "a".repeat(MAX_HEAD_BYTES)
        );
        assert_eq!(req(&long), Err(Refused::TooLarge));
    }

    #[test]
    fn refusals_answer_with_their_status() {
        let answer = |why| {
            let mut out = Vec::new();
            refusal(&mut out, &why).unwrap();
            String::from_utf8(out).unwrap()
        };
        assert!(answer(Refused::Method).starts_with("HTTP/1.1 405"));
        assert!(answer(Refused::Method).contains("Allow: GET, HEAD\r\n"));
        assert!(answer(Refused::Path).starts_with("HTTP/1.1 404"));
        assert!(answer(Refused::TooLarge).starts_with("HTTP/1.1 431"));
        assert!(answer(Refused::Gone).is_empty());
    }
}
