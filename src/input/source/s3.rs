//! `s3://bucket/key` objects: requests signed with rusty-s3 (SigV4 presigned URLs, sans-IO) and
//! sent as HTTP range requests ([`super::http`]).
//!
//! Credentials: `AWS_ACCESS_KEY_ID`, `AWS_SECRET_ACCESS_KEY` (and `AWS_SESSION_TOKEN`), else the
//! profile `AWS_PROFILE` (default `default`) of `~/.aws/credentials` (`AWS_SHARED_CREDENTIALS_FILE`),
//! else none: anonymous requests, as for public buckets (`AWS_NO_SIGN_REQUEST=YES` forces them).
//! Region: `AWS_REGION`, `AWS_DEFAULT_REGION`, the profile's `region` in `~/.aws/config`
//! (`AWS_CONFIG_FILE`), else `us-east-1`. Endpoint: `AWS_ENDPOINT_URL_S3` or `AWS_ENDPOINT_URL`
//! (MinIO, Ceph, …: path-style addressing), else AWS's (virtual-host style).

use super::http::{Http, Payload, Verb, send};
use rusty_s3::{Bucket, Credentials, S3Action, UrlStyle};
use std::io;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

fn var(name: &str) -> Option<String> {
    std::env::var(name).ok().filter(|v| !v.trim().is_empty())
}

/// The `key = value` pairs of section `section` of an INI file (AWS's credentials and config).
fn ini_section(path: Option<PathBuf>, section: &str) -> Vec<(String, String)> {
    let Some(text) = path.and_then(|p| std::fs::read_to_string(p).ok()) else {
        return Vec::new();
    };
    let mut inside = false;
    let mut out = Vec::new();
    for line in text.lines().map(str::trim) {
        if let Some(name) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            inside = name.trim() == section;
        } else if inside && let Some((k, v)) = line.split_once('=') {
            out.push((k.trim().to_string(), v.trim().to_string()));
        }
    }
    out
}

fn aws_file(var_name: &str, default: &str) -> Option<PathBuf> {
    var(var_name)
        .map(PathBuf::from)
        .or_else(|| Some(PathBuf::from(var("HOME")?).join(".aws").join(default)))
}

fn get(pairs: &[(String, String)], key: &str) -> Option<String> {
    pairs.iter().find(|(k, _)| k == key).map(|(_, v)| v.clone())
}

/// The credentials the environment gives, `None` for anonymous requests.
fn credentials(profile: &str) -> Option<Credentials> {
    if var("AWS_NO_SIGN_REQUEST").is_some_and(|v| v.eq_ignore_ascii_case("yes")) {
        return None;
    }
    let (key, secret, token) = match (var("AWS_ACCESS_KEY_ID"), var("AWS_SECRET_ACCESS_KEY")) {
        (Some(k), Some(s)) => (k, s, var("AWS_SESSION_TOKEN")),
        _ => {
            let file = ini_section(
                aws_file("AWS_SHARED_CREDENTIALS_FILE", "credentials"),
                profile,
            );
            (
                get(&file, "aws_access_key_id")?,
                get(&file, "aws_secret_access_key")?,
                get(&file, "aws_session_token"),
            )
        }
    };
    Some(match token {
        Some(t) => Credentials::new_with_token(key, secret, t),
        None => Credentials::new(key, secret),
    })
}

fn region(profile: &str) -> String {
    var("AWS_REGION")
        .or_else(|| var("AWS_DEFAULT_REGION"))
        .or_else(|| {
            let section = match profile {
                "default" => "default".to_string(),
                p => format!("profile {p}"),
            };
            get(
                &ini_section(aws_file("AWS_CONFIG_FILE", "config"), &section),
                "region",
            )
        })
        .unwrap_or_else(|| "us-east-1".to_string())
}

/// The bucket of `s3://bucket/key` as the environment addresses it, and the credentials.
fn address(bucket: &str, key: &str) -> io::Result<(Bucket, Option<Credentials>)> {
    let bad = |what: String| io::Error::new(io::ErrorKind::InvalidInput, what);
    if bucket.is_empty() || key.is_empty() {
        return Err(bad("not an S3 object: write s3://BUCKET/KEY".to_string()));
    }
    let profile = var("AWS_PROFILE").unwrap_or_else(|| "default".to_string());
    let region = region(&profile);
    let (endpoint, style) = match var("AWS_ENDPOINT_URL_S3").or_else(|| var("AWS_ENDPOINT_URL")) {
        Some(e) => (e, UrlStyle::Path),
        // Bucket names with dots cannot be host names under TLS.
        None if bucket.contains('.') => {
            (format!("https://s3.{region}.amazonaws.com"), UrlStyle::Path)
        }
        None => (
            format!("https://s3.{region}.amazonaws.com"),
            UrlStyle::VirtualHost,
        ),
    };
    let url = url::Url::parse(&endpoint)
        .map_err(|e| bad(format!("AWS_ENDPOINT_URL {endpoint}: not a URL: {e}")))?;
    let b = Bucket::new(url, style, bucket.to_string(), region)
        .map_err(|e| bad(format!("cannot address bucket {bucket}: {e}")))?;
    Ok((b, credentials(&profile)))
}

/// How long a signed URL stays valid: longer than any one request with its retries.
const SIGNED_FOR: Duration = Duration::from_secs(3600);

/// Opens `s3://bucket/key` (`name` as the user wrote it).
pub(super) fn open(name: &str, bucket: &str, key: &str) -> io::Result<Http> {
    let state = Arc::new((address(bucket, key)?, key.to_string()));
    let sign = move || -> io::Result<String> {
        let ((bucket, creds), key) = &*state;
        Ok(bucket
            .get_object(creds.as_ref(), key)
            .sign(SIGNED_FOR)
            .to_string())
    };
    Http::open(name, Some(Box::new(sign)))
}

/// An output is uploaded in parts when it is larger than this many parts: one `PUT` writes at
/// most 5 GiB, and parts are retried one by one.
const MULTIPART_FROM_PARTS: u64 = 4;

/// The size of a part (the last may be smaller): 16 MiB, more when an object needs more than
/// [`MAX_PARTS`] of them. `SWEEPTIN_S3_PART_SIZE` (bytes) sets it for the tests, which upload
/// small files in several parts (S3 refuses parts under 5 MiB but the last).
const PART: u64 = 16 << 20;

/// S3's limits: parts in one upload, the size of one object and of one `PUT`.
const MAX_PARTS: u64 = 10_000;
const MAX_OBJECT: u64 = 5 << 40;
const MAX_PUT: u64 = 5 << 30;

fn part_size() -> u64 {
    var("SWEEPTIN_S3_PART_SIZE")
        .and_then(|v| v.trim().parse().ok())
        .filter(|&n: &u64| n > 0)
        .unwrap_or(PART)
}

/// Writes `len` bytes of `file` (from its start) as `s3://bucket/key`: in one `PUT` up to four
/// parts' size (64 MiB), else in a multipart upload. Either way the object appears whole when
/// the last request completes, or not at all.
pub(super) fn put(
    name: &str,
    bucket: &str,
    key: &str,
    file: &std::fs::File,
    len: u64,
) -> io::Result<()> {
    if len > MAX_OBJECT {
        return Err(io::Error::other(format!(
            "{len} bytes: more than an S3 object may hold (5 TiB)"
        )));
    }
    let (bucket, creds) = address(bucket, key)?;
    let part = part_size();
    if len <= MULTIPART_FROM_PARTS.saturating_mul(part).min(MAX_PUT) {
        let url = bucket.put_object(creds.as_ref(), key).sign(SIGNED_FOR);
        let payload = Payload::File {
            file,
            offset: 0,
            len,
        };
        return send(name, Verb::Put, url.as_str(), payload, "no such bucket").map(drop);
    }
    let upload = Multipart {
        name,
        bucket: &bucket,
        creds: creds.as_ref(),
        key,
    };
    let id = upload.create()?;
    let _pending = Pending::register(&upload, &id);
    let part = part.max(len.div_ceil(MAX_PARTS)).min(MAX_PUT);
    match upload.parts(&id, file, len, part) {
        Ok(()) => Ok(()),
        Err(e) => match upload.abort(&id) {
            Ok(()) => Err(io::Error::new(
                e.kind(),
                format!("{e}; the upload was aborted: no object was written"),
            )),
            Err(a) => Err(io::Error::new(
                e.kind(),
                format!(
                    "{e}; the multipart upload {id} could not be aborted either ({a}): its \
                     parts stay stored until it is (aws s3api abort-multipart-upload \
                     --bucket {} --key {key} --upload-id {id}) or a lifecycle rule removes them",
                    bucket.name()
                ),
            )),
        },
    }
}

/// A multipart upload of one object: created, its parts sent in order, completed; aborted on
/// any error, so that no part is left stored.
struct Multipart<'a> {
    name: &'a str,
    bucket: &'a Bucket,
    creds: Option<&'a Credentials>,
    key: &'a str,
}

impl Multipart<'_> {
    /// A `POST` on the object with `query` (one parameter), signed: rusty-s3 signs
    /// CreateMultipartUpload and CompleteMultipartUpload only with its XML feature (a parser
    /// more), and both are one parameter and a few tags.
    fn post_url(&self, query: (&str, &str)) -> String {
        let url = self.bucket.object_url(self.key);
        match self.creds {
            Some(c) => rusty_s3::signing::sign(
                &jiff::Timestamp::now(),
                rusty_s3::Method::Post,
                url,
                c.key(),
                c.secret(),
                c.token(),
                self.bucket.region(),
                SIGNED_FOR.as_secs(),
                std::iter::once(query),
                std::iter::empty(),
            )
            .to_string(),
            None => {
                let mut url = url;
                url.query_pairs_mut().append_pair(query.0, query.1);
                url.to_string()
            }
        }
    }

    /// Starts the upload; its id.
    fn create(&self) -> io::Result<String> {
        let url = self.post_url(("uploads", ""));
        let a = send(
            self.name,
            Verb::Post,
            &url,
            Payload::Empty,
            "no such bucket",
        )?;
        xml_text(&a.body, "UploadId").ok_or_else(|| {
            io::Error::new(
                io::ErrorKind::InvalidData,
                "the server started a multipart upload without naming it (no UploadId)",
            )
        })
    }

    /// Sends the parts of `part` bytes (the last smaller) in order, then completes the upload.
    fn parts(&self, id: &str, file: &std::fs::File, len: u64, part: u64) -> io::Result<()> {
        let missing = "no such upload (the bucket was removed, or the upload aborted)";
        let mut etags = Vec::new();
        for (k, offset) in (0..len).step_by(part as usize).enumerate() {
            let number = u16::try_from(k + 1).map_err(io::Error::other)?;
            let url = self
                .bucket
                .upload_part(self.creds, self.key, number, id)
                .sign(SIGNED_FOR);
            let payload = Payload::File {
                file,
                offset,
                len: part.min(len - offset),
            };
            let count = len.div_ceil(part);
            let a = send(self.name, Verb::Put, url.as_str(), payload, missing)
                .map_err(|e| io::Error::new(e.kind(), format!("part {number} of {count}: {e}")))?;
            etags.push(a.etag.ok_or_else(|| {
                io::Error::new(
                    io::ErrorKind::InvalidData,
                    format!("the server stored part {number} without an ETag"),
                )
            })?);
        }
        let mut body = String::from("<CompleteMultipartUpload>");
        for (k, etag) in etags.iter().enumerate() {
            body.push_str(&format!(
                "<Part><PartNumber>{}</PartNumber><ETag>{}</ETag></Part>",
                k + 1,
                xml_escape(etag)
            ));
        }
        body.push_str("</CompleteMultipartUpload>");
        let url = self.post_url(("uploadId", id));
        send(
            self.name,
            Verb::Post,
            &url,
            Payload::Bytes(body.as_bytes()),
            missing,
        )
        .map(drop)
        .map_err(|e| {
            let what = format!("completing the upload of {} parts", etags.len());
            io::Error::new(e.kind(), format!("{what}: {e}"))
        })
    }

    /// Aborts the upload: the server deletes its parts.
    fn abort(&self, id: &str) -> io::Result<()> {
        let url = self
            .bucket
            .abort_multipart_upload(self.creds, self.key, id)
            .sign(SIGNED_FOR);
        send(
            self.name,
            Verb::Delete,
            url.as_str(),
            Payload::Empty,
            "no such upload",
        )
        .map(drop)
    }
}

/// The multipart uploads in progress in this process, by a serial number: what an
/// interruption aborts ([`abort_pending`]). Each is the signed `DELETE` of its abort, made
/// afresh when needed (an upload may outlast a signature).
type AbortFn = Box<dyn Fn() -> String + Send>;

fn pending() -> &'static Mutex<Vec<(u64, AbortFn)>> {
    static PENDING: Mutex<Vec<(u64, AbortFn)>> = Mutex::new(Vec::new());
    &PENDING
}

/// An upload registered in [`pending`] while it lives.
struct Pending(u64);

impl Pending {
    fn register(upload: &Multipart<'_>, id: &str) -> Pending {
        static NEXT: AtomicU64 = AtomicU64::new(0);
        let serial = NEXT.fetch_add(1, Ordering::Relaxed);
        let (bucket, creds) = (upload.bucket.clone(), upload.creds.cloned());
        let (key, id) = (upload.key.to_string(), id.to_string());
        let abort: AbortFn = Box::new(move || {
            bucket
                .abort_multipart_upload(creds.as_ref(), &key, &id)
                .sign(SIGNED_FOR)
                .to_string()
        });
        lock(pending()).push((serial, abort));
        Pending(serial)
    }
}

impl Drop for Pending {
    fn drop(&mut self) {
        lock(pending()).retain(|(s, _)| *s != self.0);
    }
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// Aborts the multipart uploads in progress (the process is being interrupted): one `DELETE`
/// each, waiting a few seconds at most, so that no part stays stored; returns how many the
/// server aborted.
pub(super) fn abort_pending() -> usize {
    let urls: Vec<String> = lock(pending()).iter().map(|(_, f)| f()).collect();
    urls.iter()
        .filter(|url| super::http::delete_once(url, ABORT_WAIT))
        .count()
}

/// How long an interrupted process waits for an abort's answer.
const ABORT_WAIT: Duration = Duration::from_secs(5);

/// The text of the first `<tag>` of an XML answer, unescaped.
fn xml_text(body: &str, tag: &str) -> Option<String> {
    let open = format!("<{tag}>");
    let from = body.find(&open)? + open.len();
    let to = from + body[from..].find(&format!("</{tag}>"))?;
    let text = body[from..to].trim();
    Some(
        text.replace("&quot;", "\"")
            .replace("&apos;", "'")
            .replace("&lt;", "<")
            .replace("&gt;", ">")
            .replace("&amp;", "&"),
    )
}

fn xml_escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// Checks that the bucket of `s3://bucket/key` can be written, before a run's work: a signed
/// `HEAD` on the bucket. "No such bucket" and a failure to reach the endpoint are errors; an
/// access denied is not (credentials allowed to put objects may not be allowed to list them,
/// which `HEAD` needs): the upload then tells.
pub(super) fn check_bucket(name: &str, bucket: &str, key: &str) -> io::Result<()> {
    let (b, creds) = address(bucket, key)?;
    let url = b.head_bucket(creds.as_ref()).sign(SIGNED_FOR);
    match send(
        name,
        Verb::Head,
        url.as_str(),
        Payload::Empty,
        "no such bucket",
    ) {
        Err(e) if e.kind() == io::ErrorKind::PermissionDenied => Ok(()),
        r => r.map(drop),
    }
}

/// The size of `s3://bucket/key` by a signed `HEAD`; `None` when there is no such object.
pub(super) fn size(name: &str, bucket: &str, key: &str) -> io::Result<Option<u64>> {
    let (b, creds) = address(bucket, key)?;
    let url = b.head_object(creds.as_ref(), key).sign(SIGNED_FOR);
    match send(
        name,
        Verb::Head,
        url.as_str(),
        Payload::Empty,
        "no such object",
    ) {
        Ok(a) => a.length.map(Some).ok_or_else(|| {
            io::Error::new(
                io::ErrorKind::InvalidData,
                "the server answered HEAD without a Content-Length",
            )
        }),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(e),
    }
}

/// Deletes `s3://bucket/key` (DeleteObject; no such object is no error, as S3 answers it).
pub(super) fn delete(name: &str, bucket: &str, key: &str) -> io::Result<()> {
    let (b, creds) = address(bucket, key)?;
    let url = b.delete_object(creds.as_ref(), key).sign(SIGNED_FOR);
    match send(
        name,
        Verb::Delete,
        url.as_str(),
        Payload::Empty,
        "no such object",
    ) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(()),
        r => r.map(drop),
    }
}

/// The first key of `bucket` that starts with `prefix` (ListObjectsV2, one key), if any. Signed
/// by hand as a multipart upload's requests are (rusty-s3 lists only with its XML feature).
pub(super) fn first_key(name: &str, bucket: &str, prefix: &str) -> io::Result<Option<String>> {
    let (b, creds) = address(bucket, if prefix.is_empty() { "-" } else { prefix })?;
    let query = [("list-type", "2"), ("max-keys", "1"), ("prefix", prefix)];
    let url = match &creds {
        Some(c) => rusty_s3::signing::sign(
            &jiff::Timestamp::now(),
            rusty_s3::Method::Get,
            b.base_url().clone(),
            c.key(),
            c.secret(),
            c.token(),
            b.region(),
            SIGNED_FOR.as_secs(),
            query.iter().copied(),
            std::iter::empty(),
        )
        .to_string(),
        None => {
            let mut url = b.base_url().clone();
            url.query_pairs_mut().extend_pairs(query);
            url.to_string()
        }
    };
    let a = send(name, Verb::Get, &url, Payload::Empty, "no such bucket")?;
    Ok(xml_text(&a.body, "Key"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xml_answers() {
        let body = "<?xml version=\"1.0\"?><InitiateMultipartUploadResult><Bucket>b</Bucket>\
                    <UploadId> a&amp;b </UploadId></InitiateMultipartUploadResult>";
        assert_eq!(xml_text(body, "UploadId").as_deref(), Some("a&b"));
        assert_eq!(xml_text(body, "Key"), None);
        assert_eq!(xml_escape("\"x\"<&"), "\"x\"&lt;&amp;");
    }
}
