//! The language server's stdio transport: base-protocol framing (`Content-Length`
//! headers) with limits. `lsp-server`'s own reader allocates whatever a header claims
//! (`Content-Length: 1000000000000` aborts the process) and stops at the first
//! malformed message; this one skips an oversized or malformed message, tells the
//! server (which shows the user an error and keeps serving), and goes on.

use crossbeam_channel::{unbounded, Sender};
use lsp_server::{Connection, Message, Notification};
use std::io::{self, BufRead, Read, Write};
use std::thread::JoinHandle;

/// The largest message the server reads, in bytes: a document at the size limit, with
/// room for JSON escapes.
pub const MAX_MESSAGE_BYTES: usize = 4 * crate::syntax::MAX_SOURCE_BYTES;
/// The longest header line.
const MAX_HEADER_LINE: usize = 1024;

/// The notification the reader sends the server for a message it skipped.
pub const SKIPPED: &str = "$/sdfc/skippedMessage";

/// The reader and writer threads of a stdio connection.
pub struct Threads {
    reader: JoinHandle<io::Result<()>>,
    writer: JoinHandle<io::Result<()>>,
}

impl Threads {
    /// Waits for the writer to flush what the server sent. The reader is not waited for:
    /// it may be blocked on input that will never come.
    pub fn join(self) -> io::Result<()> {
        drop(self.reader);
        self.writer
            .join()
            .map_err(|_| io::Error::other("the writer thread panicked"))?
    }
}

/// A connection over standard input and output.
pub fn stdio() -> (Connection, Threads) {
    let (to_server, receiver) = unbounded::<Message>();
    let (sender, from_server) = unbounded::<Message>();
    let reader = std::thread::Builder::new()
        .name(String::from("sdfc-lsp-reader"))
        .spawn(move || read_loop(&mut io::stdin().lock(), &to_server))
        .expect("a thread for the reader");
    let writer = std::thread::Builder::new()
        .name(String::from("sdfc-lsp-writer"))
        .spawn(move || {
            let stdout = io::stdout();
            let mut out = stdout.lock();
            for msg in from_server {
                msg.write(&mut out)?;
            }
            out.flush()
        })
        .expect("a thread for the writer");
    (Connection { sender, receiver }, Threads { reader, writer })
}

/// Reads messages until the input ends, the server hangs up, or `exit` arrives.
pub fn read_loop(input: &mut impl BufRead, to_server: &Sender<Message>) -> io::Result<()> {
    loop {
        let length = match read_headers(input)? {
            Headers::End => return Ok(()),
            Headers::Length(n) => n,
            Headers::Bad(why) => {
                // Framing is lost: say so, and stop reading.
                let _ = to_server.send(skipped(&why));
                return Ok(());
            }
        };
        if length > MAX_MESSAGE_BYTES {
            let why = format!(
                "a message of {length} bytes is over the limit of {MAX_MESSAGE_BYTES} bytes; it was skipped"
            );
            if to_server.send(skipped(&why)).is_err() {
                return Ok(());
            }
            let skipped = io::copy(&mut input.take(length as u64), &mut io::sink())?;
            if skipped < length as u64 {
                return Ok(());
            }
            continue;
        }
        let mut body = vec![0; length];
        if input.read_exact(&mut body).is_err() {
            return Ok(());
        }
        let msg = match serde_json::from_slice::<Message>(&body) {
            Ok(m) => m,
            Err(e) => {
                let why = format!("a message that is not JSON-RPC was skipped: {e}");
                if to_server.send(skipped(&why)).is_err() {
                    return Ok(());
                }
                continue;
            }
        };
        let exit = matches!(&msg, Message::Notification(n) if n.method == "exit");
        if to_server.send(msg).is_err() || exit {
            return Ok(());
        }
    }
}

fn skipped(why: &str) -> Message {
    Message::Notification(Notification::new(
        SKIPPED.to_string(),
        serde_json::json!({ "message": why }),
    ))
}

enum Headers {
    Length(usize),
    End,
    Bad(String),
}

/// Reads one message's headers: `Content-Length` is required, others are ignored.
fn read_headers(input: &mut impl BufRead) -> io::Result<Headers> {
    let mut length = None;
    let mut first = true;
    loop {
        let mut line = Vec::new();
        let n = input
            .by_ref()
            .take(MAX_HEADER_LINE as u64)
            .read_until(b'\n', &mut line)?;
        if n == 0 {
            return Ok(if first {
                Headers::End
            } else {
                Headers::Bad(String::from("the input ended inside a message's headers"))
            });
        }
        first = false;
        if !line.ends_with(b"\n") {
            return Ok(Headers::Bad(format!(
                "a header line longer than {MAX_HEADER_LINE} bytes"
            )));
        }
        let line = String::from_utf8_lossy(&line);
        let line = line.trim_end_matches(['\r', '\n']);
        if line.is_empty() {
            return Ok(match length {
                Some(n) => Headers::Length(n),
                None => Headers::Bad(String::from("a message without Content-Length")),
            });
        }
        if let Some((name, value)) = line.split_once(':') {
            if name.trim().eq_ignore_ascii_case("content-length") {
                match value.trim().parse::<usize>() {
                    Ok(n) => length = Some(n),
                    Err(_) => {
                        return Ok(Headers::Bad(format!(
                            "a Content-Length that is not a number: {}",
                            crate::diagnostic::quote(value.trim())
                        )))
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(body: &str) -> String {
        format!("Content-Length: {}\r\n\r\n{body}", body.len())
    }

    fn read_all(input: &str) -> Vec<Message> {
        let (tx, rx) = unbounded();
        read_loop(&mut io::Cursor::new(input.as_bytes().to_vec()), &tx).unwrap();
        drop(tx);
        rx.into_iter().collect()
    }

    fn method(m: &Message) -> &str {
        match m {
            Message::Notification(n) => &n.method,
            Message::Request(r) => &r.method,
            Message::Response(_) => "response",
        }
    }

    #[test]
    fn oversized_and_malformed_messages_are_skipped_and_reported() {
        let good = r#"{"jsonrpc":"2.0","id":1,"method":"shutdown"}"#;
        let input = format!(
            "Content-Length: {}\r\n\r\n{}{}{}",
            MAX_MESSAGE_BYTES + 1,
            "x".repeat(MAX_MESSAGE_BYTES + 1),
            frame("{not json"),
            frame(good)
        );
        let got = read_all(&input);
        let methods: Vec<&str> = got.iter().map(method).collect();
        assert_eq!(methods, [SKIPPED, SKIPPED, "shutdown"]);
    }

    #[test]
    fn a_huge_claimed_length_does_not_allocate_it() {
        // Claims 10^12 bytes and sends a few: skipped, then the input ends.
        let got = read_all("Content-Length: 1000000000000\r\n\r\n{}");
        assert_eq!(got.len(), 1);
        assert_eq!(method(&got[0]), SKIPPED);
    }

    #[test]
    fn the_reader_stops_after_exit() {
        let input = frame(r#"{"jsonrpc":"2.0","method":"exit"}"#)
            + &frame(r#"{"jsonrpc":"2.0","id":1,"method":"shutdown"}"#);
        let got = read_all(&input);
        assert_eq!(got.len(), 1);
        assert_eq!(method(&got[0]), "exit");
    }

    #[test]
    fn a_missing_length_ends_the_connection_with_a_report() {
        let got = read_all("Content-Type: x\r\n\r\n{}");
        assert_eq!(got.len(), 1);
        assert_eq!(method(&got[0]), SKIPPED);
    }
}
