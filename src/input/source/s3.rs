//! `s3://bucket/key` objects: requests signed with rusty-s3 (SigV4 presigned URLs, sans-IO) and
//! sent as HTTP range requests ([`super::http`]).
//!
//! Credentials: `AWS_ACCESS_KEY_ID`, `AWS_SECRET_ACCESS_KEY` (and `AWS_SESSION_TOKEN`), else the
//! profile `AWS_PROFILE` (default `default`) of `~/.aws/credentials` (`AWS_SHARED_CREDENTIALS_FILE`),
//! else none: anonymous requests, as for public buckets (`AWS_NO_SIGN_REQUEST=YES` forces them).
//! Region: `AWS_REGION`, `AWS_DEFAULT_REGION`, the profile's `region` in `~/.aws/config`
//! (`AWS_CONFIG_FILE`), else `us-east-1`. Endpoint: `AWS_ENDPOINT_URL_S3` or `AWS_ENDPOINT_URL`
//! (MinIO, Ceph, …: path-style addressing), else AWS's (virtual-host style).

use super::http::Http;
use rusty_s3::{Bucket, Credentials, S3Action, UrlStyle};
use std::io;
use std::path::PathBuf;
use std::sync::Arc;
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

/// The largest object one `PUT` may write (S3's limit).
const MAX_PUT: u64 = 5 << 30;

/// Writes `len` bytes of `file` (from its start) as `s3://bucket/key` in one `PUT`: the object
/// appears whole when the request completes, or not at all.
pub(super) fn put(
    name: &str,
    bucket: &str,
    key: &str,
    file: &std::fs::File,
    len: u64,
) -> io::Result<()> {
    if len > MAX_PUT {
        return Err(io::Error::other(format!(
            "{len} bytes: more than one S3 PUT writes (5 GiB; multipart uploads are not \
             written yet): write it to a local file and copy it (aws s3 cp)"
        )));
    }
    let (bucket, creds) = address(bucket, key)?;
    let url = bucket.put_object(creds.as_ref(), key).sign(SIGNED_FOR);
    super::http::put(name, url.as_str(), file, len)
}
