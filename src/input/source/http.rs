//! An HTTP(S) object read by range requests (ureq), with its identity checked on every answer
//! and bounded retries. S3 objects are read through it with presigned URLs ([`super::s3`]).

use std::fs::File;
use std::io::{self, Read};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// Attempts per request before giving up (the first and the retries).
const ATTEMPTS: u32 = 5;

/// The wait before the first retry, doubled at each one (0.2 s, 0.4, 0.8, 1.6).
const BACKOFF: Duration = Duration::from_millis(200);

/// Makes the URL of each request (an S3 object's is signed afresh, so long runs never use an
/// expired signature).
pub(super) type UrlFn = Box<dyn Fn() -> io::Result<String> + Send + Sync>;

/// A remote object as first seen: its size and identity, and how to ask for its bytes.
pub(super) struct Http {
    name: String,
    url: Option<UrlFn>,
    len: u64,
    etag: Option<String>,
    modified: Option<String>,
    /// The whole object, when the server ignored `Range` at the first request.
    whole: Option<File>,
    warned: AtomicBool,
}

/// What went wrong with one attempt: worth retrying, or not.
enum Fault {
    Retry(String),
    Fail(io::Error),
}

fn agent() -> &'static ureq::Agent {
    static AGENT: OnceLock<ureq::Agent> = OnceLock::new();
    AGENT.get_or_init(|| {
        ureq::Agent::config_builder()
            .http_status_as_error(false)
            .user_agent(concat!("sweeptin/", env!("CARGO_PKG_VERSION")))
            .build()
            .into()
    })
}

/// A GET of `url` with the timeouts of `--io-timeout` as they are now (set per request: the
/// agent is made at the first request, which may come before the options are read); its body
/// may take `body` times that.
fn get(url: &str, body: u64) -> ureq::RequestBuilder<ureq::typestate::WithoutBody> {
    let secs = super::io_timeout();
    agent()
        .get(url)
        .config()
        .timeout_connect(Some(Duration::from_secs(secs)))
        .timeout_recv_response(Some(Duration::from_secs(secs)))
        .timeout_recv_body(Some(Duration::from_secs(body * secs)))
        .build()
}

/// The body of a range request (at most 8 MiB) may take this many times `--io-timeout`.
const RANGE_BODY: u64 = 2;

/// The first request's body may take this many times `--io-timeout`: a server that ignores
/// `Range` sends the whole object then (an hour at the default).
const WHOLE_BODY: u64 = 60;

fn header(r: &ureq::http::Response<ureq::Body>, name: &str) -> Option<String> {
    r.headers()
        .get(name)
        .and_then(|v| v.to_str().ok())
        .map(str::to_string)
}

/// A `Content-Range`: the first and last byte (`None` for `*`) and the total (`None` for `*`).
type ContentRange = (Option<(u64, u64)>, Option<u64>);

/// `bytes FIRST-LAST/TOTAL` (TOTAL may be `*`), or `bytes */TOTAL`.
fn content_range(v: &str) -> Option<ContentRange> {
    let v = v.trim().strip_prefix("bytes")?.trim();
    let (range, total) = v.split_once('/')?;
    let total = match total.trim() {
        "*" => None,
        t => Some(t.parse().ok()?),
    };
    let range = match range.trim() {
        "*" => None,
        r => {
            let (a, b) = r.split_once('-')?;
            Some((a.trim().parse().ok()?, b.trim().parse().ok()?))
        }
    };
    Some((range, total))
}

fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, msg)
}

/// What a status other than a success means for the user; a 404 means `missing` ("no such
/// object", or "no such bucket" for a write).
fn refused(status: u16, missing: &str) -> Fault {
    let why = match status {
        500..=599 | 429 | 408 => return Fault::Retry(format!("the server answered HTTP {status}")),
        404 => format!("{missing} (HTTP 404): check the URL"),
        401 | 403 => format!(
            "access denied (HTTP {status}): check the URL and the credentials \
             (AWS_ACCESS_KEY_ID/AWS_SECRET_ACCESS_KEY or AWS_PROFILE for s3://)"
        ),
        s => format!("the server refused the request (HTTP {s})"),
    };
    let kind = match status {
        404 => io::ErrorKind::NotFound,
        401 | 403 => io::ErrorKind::PermissionDenied,
        _ => io::ErrorKind::Other,
    };
    Fault::Fail(io::Error::new(kind, why))
}

/// Runs `attempt` until it succeeds, fails for good, or [`ATTEMPTS`] are spent; each retry is
/// logged on stderr.
fn retried<T>(name: &str, mut attempt: impl FnMut() -> Result<T, Fault>) -> io::Result<T> {
    let mut wait = BACKOFF;
    for k in 1..=ATTEMPTS {
        match attempt() {
            Ok(t) => return Ok(t),
            Err(Fault::Fail(e)) => return Err(e),
            Err(Fault::Retry(what)) if k == ATTEMPTS => {
                return Err(io::Error::other(format!(
                    "{what}; gave up after {ATTEMPTS} attempts"
                )));
            }
            Err(Fault::Retry(what)) => {
                eprintln!(
                    "sweeptin: {name}: {what}; retrying in {:.1} s (attempt {} of {ATTEMPTS})",
                    wait.as_secs_f64(),
                    k + 1
                );
                std::thread::sleep(wait);
                wait *= 2;
            }
        }
    }
    unreachable!("the last attempt returns")
}

fn transport(e: &ureq::Error) -> Fault {
    match e {
        ureq::Error::BadUri(_) | ureq::Error::Http(_) | ureq::Error::InvalidProxyUrl => {
            Fault::Fail(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("not a valid URL: {e}"),
            ))
        }
        e => Fault::Retry(format!("the request failed: {e}")),
    }
}

/// What a request that writes sends.
#[derive(Clone, Copy)]
pub(super) enum Payload<'a> {
    /// No body.
    Empty,
    /// These bytes.
    Bytes(&'a [u8]),
    /// `len` bytes of `file` from `offset`, read from the file at each attempt.
    File {
        file: &'a File,
        offset: u64,
        len: u64,
    },
}

impl Payload<'_> {
    fn len(&self) -> u64 {
        match self {
            Payload::Empty => 0,
            Payload::Bytes(b) => b.len() as u64,
            Payload::File { len, .. } => *len,
        }
    }
}

/// The method of a request that writes, or that asks about a bucket or an object (a `GET`
/// here lists a bucket: its answer is small).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Verb {
    Put,
    Post,
    Delete,
    Head,
    Get,
}

/// A successful answer: its ETag, `Content-Length` (a `HEAD`'s is the object's size) and body
/// (at most 1 MiB kept).
pub(super) struct Answer {
    pub(super) etag: Option<String>,
    pub(super) length: Option<u64>,
    pub(super) body: String,
}

/// The `<Code>` of an S3 error document, if `body` is one.
fn s3_error_code(body: &str) -> Option<&str> {
    let rest = &body[body.find("<Error>")?..];
    let code = &rest[rest.find("<Code>")? + 6..];
    Some(code[..code.find("</Code>")?].trim())
}

/// Sends `verb` to `url` with `payload`, retried as reads are; `name` is the destination as the
/// user wrote it, `missing` what a 404 means ("no such bucket"). An S3 error document in a
/// `200` answer (S3 may answer a multipart upload's completion so) is retried.
pub(super) fn send(
    name: &str,
    verb: Verb,
    url: &str,
    payload: Payload<'_>,
    missing: &str,
) -> io::Result<Answer> {
    use std::io::{Seek, SeekFrom};
    retried(name, || {
        let secs = super::io_timeout();
        let len = payload.len();
        // The body's time grows with its size (at least 1 MB/s), over the answer's wait; the
        // answer's body (an S3 completion's, which may come slowly) may take 60 times the wait.
        let t = |s: u64| Some(Duration::from_secs(s));
        let (send_secs, answer_secs) = (secs + len / 1_000_000, WHOLE_BODY * secs);
        let r = match verb {
            Verb::Put | Verb::Post => {
                let b = match verb {
                    Verb::Put => agent().put(url),
                    _ => agent().post(url),
                };
                let b = b
                    .config()
                    .timeout_connect(t(secs))
                    .timeout_send_body(t(send_secs))
                    .timeout_recv_response(t(secs))
                    .timeout_recv_body(t(answer_secs))
                    .build()
                    .header("Content-Length", &len.to_string());
                match payload {
                    Payload::Empty => b.send_empty(),
                    Payload::Bytes(bytes) => b.send(bytes),
                    Payload::File { file, offset, len } => {
                        let mut f = file.try_clone().map_err(Fault::Fail)?;
                        f.seek(SeekFrom::Start(offset)).map_err(Fault::Fail)?;
                        let mut part = f.take(len);
                        b.send(ureq::SendBody::from_reader(&mut part))
                    }
                }
            }
            Verb::Delete | Verb::Head | Verb::Get => {
                let b = match verb {
                    Verb::Delete => agent().delete(url),
                    Verb::Get => agent().get(url),
                    _ => agent().head(url),
                };
                b.config()
                    .timeout_connect(t(secs))
                    .timeout_recv_response(t(secs))
                    .timeout_recv_body(t(answer_secs))
                    .build()
                    .call()
            }
        }
        .map_err(|e| transport(&e))?;
        let status = r.status().as_u16();
        let etag = header(&r, "etag");
        let length = header(&r, "content-length").and_then(|v| v.trim().parse().ok());
        let body = if verb == Verb::Head {
            String::new()
        } else {
            let mut text = Vec::new();
            (&mut r.into_body().as_reader())
                .take(1 << 20)
                .read_to_end(&mut text)
                .map_err(|e| Fault::Retry(format!("the connection broke in the answer: {e}")))?;
            String::from_utf8_lossy(&text).into_owned()
        };
        let code = s3_error_code(&body);
        match status {
            200..=299 => match code {
                None => Ok(Answer { etag, length, body }),
                Some(c) => Err(Fault::Retry(format!(
                    "the server answered HTTP {status} with the error {c}"
                ))),
            },
            s => Err(match (refused(s, missing), code) {
                (Fault::Fail(e), Some(c)) => {
                    Fault::Fail(io::Error::new(e.kind(), format!("{e} (S3 error {c})")))
                }
                (f, _) => f,
            }),
        }
    })
}

/// One `DELETE` of `url`, waiting at most `wait` in all, not retried (an interrupted process
/// aborting its uploads): whether the server answered with a success.
pub(super) fn delete_once(url: &str, wait: Duration) -> bool {
    agent()
        .delete(url)
        .config()
        .timeout_global(Some(wait))
        .build()
        .call()
        .is_ok_and(|r| r.status().is_success())
}

impl Http {
    /// Opens `name` (the URL as given; `url` makes each request's URL when it differs, as for
    /// S3): one request for byte 0 tells the size, the identity and whether ranges work.
    pub(super) fn open(name: &str, url: Option<UrlFn>) -> io::Result<Http> {
        let mut http = Http {
            name: name.to_string(),
            url,
            len: 0,
            etag: None,
            modified: None,
            whole: None,
            warned: AtomicBool::new(false),
        };
        retried(name, || http.probe())?;
        Ok(http)
    }

    fn url(&self) -> Result<String, Fault> {
        match &self.url {
            Some(f) => f().map_err(Fault::Fail),
            None => Ok(self.name.clone()),
        }
    }

    fn probe(&mut self) -> Result<(), Fault> {
        let r = get(&self.url()?, WHOLE_BODY)
            .header("Range", "bytes=0-0")
            .call()
            .map_err(|e| transport(&e))?;
        let status = r.status().as_u16();
        self.etag = header(&r, "etag");
        self.modified = header(&r, "last-modified");
        let range = header(&r, "content-range").and_then(|v| content_range(&v));
        match status {
            206 => {
                let Some((_, Some(total))) = range else {
                    return Err(Fault::Fail(invalid(
                        "the server answered a range request without a valid Content-Range".into(),
                    )));
                };
                self.len = total;
                let _ = r.into_body().as_reader().read_to_end(&mut Vec::new());
                Ok(())
            }
            // An empty object has no byte 0.
            416 if matches!(range, Some((None, Some(0)))) => Ok(()),
            200 => {
                eprintln!(
                    "sweeptin: warning: {}: the server ignores range requests: the whole object \
                     is read once, sequentially",
                    self.name
                );
                let announced: Option<u64> =
                    header(&r, "content-length").and_then(|v| v.parse().ok());
                let mut file = tempfile::tempfile().map_err(Fault::Fail)?;
                let got = io::copy(&mut r.into_body().as_reader(), &mut file)
                    .map_err(|e| Fault::Retry(format!("the connection broke: {e}")))?;
                if announced.is_some_and(|n| n != got) {
                    return Err(Fault::Retry(format!(
                        "the body ended after {got} of {} bytes",
                        announced.unwrap_or(0)
                    )));
                }
                self.len = got;
                self.whole = Some(file);
                Ok(())
            }
            s => Err(refused(s, "no such object")),
        }
    }

    fn changed(&self, what: &str) -> io::Error {
        invalid(format!(
            "the object changed while it was being read ({what}; it was {}): nothing read \
             from the two versions is mixed; run again once it is stable",
            super::Object::identity(self)
        ))
    }

    /// One range request for `buf.len()` bytes at `offset`.
    fn fetch(&self, offset: u64, buf: &mut [u8]) -> Result<(), Fault> {
        let last = offset + buf.len() as u64 - 1;
        let mut req =
            get(&self.url()?, RANGE_BODY).header("Range", &format!("bytes={offset}-{last}"));
        // `If-Match` compares strongly: a weak ETag (`W/"…"`) would never match, so it is only
        // compared with the answer's.
        if let Some(tag) = self.etag.as_ref().filter(|t| !t.starts_with("W/")) {
            req = req.header("If-Match", tag);
        } else if let Some(m) = self.modified.as_ref().filter(|_| self.etag.is_none()) {
            req = req.header("If-Unmodified-Since", m);
        }
        let r = req.call().map_err(|e| transport(&e))?;
        let status = r.status().as_u16();
        if status == 412 {
            return Err(Fault::Fail(
                self.changed("the server says it no longer matches"),
            ));
        }
        if !matches!(status, 200 | 206) {
            return Err(refused(status, "no such object"));
        }
        let (etag, modified) = (header(&r, "etag"), header(&r, "last-modified"));
        if let (Some(was), Some(now)) = (&self.etag, &etag)
            && was != now
        {
            return Err(Fault::Fail(self.changed(&format!("its ETag is now {now}"))));
        }
        if self.etag.is_none()
            && let (Some(was), Some(now)) = (&self.modified, &modified)
            && was != now
        {
            return Err(Fault::Fail(
                self.changed(&format!("it is now last modified {now}")),
            ));
        }
        let mut skip = 0;
        if status == 206 {
            let range = header(&r, "content-range");
            match range.as_deref().and_then(content_range) {
                Some((Some((a, b)), total)) if (a, b) == (offset, last) => {
                    if total.is_some_and(|t| t != self.len) {
                        return Err(Fault::Fail(
                            self.changed(&format!("it now has {} bytes", total.unwrap_or(0))),
                        ));
                    }
                }
                _ => {
                    return Err(Fault::Fail(invalid(format!(
                        "asked for bytes {offset}-{last}, the server answered Content-Range {}",
                        range.as_deref().unwrap_or("(none)")
                    ))));
                }
            }
        } else {
            let length: Option<u64> = header(&r, "content-length").and_then(|v| v.parse().ok());
            if length.is_some_and(|n| n != self.len) {
                return Err(Fault::Fail(
                    self.changed(&format!("it now has {} bytes", length.unwrap_or(0))),
                ));
            }
            if !self.warned.swap(true, Ordering::Relaxed) {
                eprintln!(
                    "sweeptin: warning: {}: the server ignored a range request: reading from \
                     the first byte",
                    self.name
                );
            }
            skip = offset;
        }
        let mut body = r.into_body();
        let mut read = body.as_reader();
        let broke = |e: io::Error| {
            Fault::Retry(format!(
                "the connection broke while reading bytes {offset}-{last}: {e}"
            ))
        };
        io::copy(&mut (&mut read).take(skip), &mut io::sink()).map_err(broke)?;
        read.read_exact(buf).map_err(|e| {
            if e.kind() == io::ErrorKind::UnexpectedEof {
                Fault::Retry(format!(
                    "the body of bytes {offset}-{last} ended early (a short answer)"
                ))
            } else {
                broke(e)
            }
        })
    }
}

impl super::Object for Http {
    fn len(&self) -> u64 {
        self.len
    }

    fn read_at(&self, offset: u64, buf: &mut [u8]) -> io::Result<()> {
        if offset
            .checked_add(buf.len() as u64)
            .is_none_or(|end| end > self.len)
        {
            return Err(io::Error::new(
                io::ErrorKind::UnexpectedEof,
                format!(
                    "bytes {offset}+{} lie past the end of the object ({} bytes)",
                    buf.len(),
                    self.len
                ),
            ));
        }
        if let Some(f) = &self.whole {
            return super::local::read_file_at(f, offset, buf);
        }
        retried(&self.name, || self.fetch(offset, buf))
    }

    fn identity(&self) -> String {
        match (&self.etag, &self.modified) {
            (Some(t), _) => format!("ETag {t}, {} bytes", self.len),
            (None, Some(m)) => format!("last modified {m}, {} bytes", self.len),
            (None, None) => format!("{} bytes", self.len),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::content_range;

    #[test]
    fn content_ranges() {
        assert_eq!(
            content_range("bytes 0-0/1234"),
            Some((Some((0, 0)), Some(1234)))
        );
        assert_eq!(content_range("bytes */0"), Some((None, Some(0))));
        assert_eq!(content_range("bytes 5-9/*"), Some((Some((5, 9)), None)));
        assert_eq!(content_range("items 0-1/2"), None);
    }
}
