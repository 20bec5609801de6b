//! Servers for the remote-input tests, started by the tests on 127.0.0.1 and a free port:
//! nginx serving a folder (ranges, ETags), moto's S3 server (a bucket made with credentials,
//! path-style addressing), and a tiny HTTP server written here whose faults the tests choose
//! (dropped connections, 503s, an object replaced between two range reads, no range support).
//! Under `CI=true` a missing nginx or moto fails the test (`data::tool`).

#![allow(dead_code)]

use super::data;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Runs the command with `args` and the environment variables `env` added.
pub fn sweeptin<V: AsRef<std::ffi::OsStr>>(
    args: &[&str],
    env: &[(&str, V)],
) -> std::process::Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_sweeptin"));
    c.args(args);
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().unwrap()
}

/// A command's standard error.
pub fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A port nobody listens on now.
fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

fn wait_for(port: u16, what: &str, child: &mut Child) {
    let start = Instant::now();
    while TcpStream::connect(("127.0.0.1", port)).is_err() {
        if let Ok(Some(status)) = child.try_wait() {
            panic!("{what} exited at start: {status}");
        }
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "{what} did not listen on port {port} within 30 s"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// nginx serving `root` at [`Nginx::url`]; stopped when dropped.
pub struct Nginx {
    child: Child,
    dir: tempfile::TempDir,
    pub port: u16,
}

impl Nginx {
    /// Starts nginx over `root`, or `None` (locally) when nginx is not installed.
    pub fn start(root: &Path, test: &str) -> Option<Nginx> {
        // Debian installs it in /usr/sbin, not on every user's PATH.
        let nginx = if Path::new("/usr/sbin/nginx").exists() {
            "/usr/sbin/nginx".to_string()
        } else if data::tool("nginx", test) {
            "nginx".to_string()
        } else {
            return None;
        };
        let dir = tempfile::tempdir().unwrap();
        let port = free_port();
        // As root, nginx's workers would run as `nobody`, who cannot read a private temp dir.
        // One process (no master): killing it when the test ends leaves no orphan worker.
        let user = if nix_uid() == 0 {
            "user root root;"
        } else {
            ""
        };
        let conf = format!(
            "{user}\nmaster_process off;\nworker_processes 1;\npid {d}/nginx.pid;\nerror_log {d}/error.log;\n\
             events {{ worker_connections 64; }}\n\
             http {{\n  log_format bytes '$request $status $body_bytes_sent';\n\
               access_log {d}/access.log bytes;\n\
               client_body_temp_path {d}; proxy_temp_path {d}; fastcgi_temp_path {d};\n\
               uwsgi_temp_path {d}; scgi_temp_path {d};\n\
               server {{ listen 127.0.0.1:{port}; root {root}; location / {{ }} }}\n}}\n",
            d = dir.path().display(),
            root = root.display()
        );
        std::fs::write(dir.path().join("nginx.conf"), conf).unwrap();
        let mut child = Command::new(&nginx)
            .arg("-p")
            .arg(dir.path())
            .arg("-c")
            .arg(dir.path().join("nginx.conf"))
            .args(["-g", "daemon off;"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        wait_for(port, "nginx", &mut child);
        Some(Nginx { child, dir, port })
    }

    /// The URL of `name` under the served folder.
    pub fn url(&self, name: &str) -> String {
        format!("http://127.0.0.1:{}/{name}", self.port)
    }

    /// The body bytes nginx sent so far (its access log) and the number of requests.
    pub fn sent(&self) -> (u64, usize) {
        let log = std::fs::read_to_string(self.dir.path().join("access.log")).unwrap_or_default();
        let bytes = log
            .lines()
            .filter_map(|l| l.rsplit(' ').next()?.parse::<u64>().ok())
            .sum();
        (bytes, log.lines().count())
    }
}

impl Drop for Nginx {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn nix_uid() -> u32 {
    Command::new("id")
        .arg("-u")
        .output()
        .ok()
        .and_then(|o| String::from_utf8_lossy(&o.stdout).trim().parse().ok())
        .unwrap_or(1)
}

/// moto's S3 server with one bucket; stopped when dropped.
pub struct Moto {
    child: Child,
    pub endpoint: String,
}

/// The credentials the tests give moto (any pair works; they must be given).
pub const KEY: &str = "testkey";
pub const SECRET: &str = "testsecret";

impl Moto {
    /// Starts `moto_server`, or `None` (locally) when it is not installed.
    pub fn start(test: &str) -> Option<Moto> {
        Moto::start_with(test, &[])
    }

    /// Starts `moto_server` with `env` (its settings: `S3_UPLOAD_PART_MIN_SIZE`…).
    pub fn start_with(test: &str, env: &[(&str, &str)]) -> Option<Moto> {
        if !data::tool("moto_server", test) || !data::python(&["boto3"], test) {
            return None;
        }
        let port = free_port();
        let mut child = Command::new("moto_server")
            .args(["-H", "127.0.0.1", "-p", &port.to_string()])
            .envs(env.iter().copied())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        wait_for(port, "moto_server", &mut child);
        Some(Moto {
            child,
            endpoint: format!("http://127.0.0.1:{port}"),
        })
    }

    /// Runs `body` in Python with `s3`, a boto3 client of this server.
    fn boto(&self, body: &str) -> std::process::Output {
        let script = format!(
            "import boto3, sys\n\
             s3 = boto3.client('s3', endpoint_url='{e}', aws_access_key_id='{KEY}',\n\
                 aws_secret_access_key='{SECRET}', region_name='us-east-1')\n{body}",
            e = self.endpoint
        );
        Command::new("python3")
            .args(["-c", &script])
            .output()
            .unwrap()
    }

    /// Uploads `file` as `s3://bucket/key` (making the bucket), with boto3.
    pub fn put(&self, bucket: &str, key: &str, file: &Path) {
        let o = self.boto(&format!(
            "try:\n    s3.create_bucket(Bucket='{bucket}')\n\
             except s3.exceptions.BucketAlreadyOwnedByYou:\n    pass\n\
             s3.upload_file('{f}', '{bucket}', '{key}')\n",
            f = file.display()
        ));
        assert!(
            o.status.success(),
            "boto3 upload: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }

    /// Downloads `s3://bucket/key` to `file`, with boto3; `false` when there is no such object.
    pub fn get(&self, bucket: &str, key: &str, file: &Path) -> bool {
        self.boto(&format!(
            "try:\n    s3.download_file('{bucket}', '{key}', '{f}')\n\
             except Exception as x:\n    print(x, file=sys.stderr); sys.exit(1)\n",
            f = file.display()
        ))
        .status
        .success()
    }

    /// Makes the bucket `bucket`, with boto3.
    pub fn make_bucket(&self, bucket: &str) {
        let o = self.boto(&format!("s3.create_bucket(Bucket='{bucket}')\n"));
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }

    /// The ETag of `s3://bucket/key` (`"HEX-N"` for an object uploaded in N parts), `None`
    /// when there is no such object.
    pub fn etag(&self, bucket: &str, key: &str) -> Option<String> {
        let o = self.boto(&format!(
            "try:\n    print(s3.head_object(Bucket='{bucket}', Key='{key}')['ETag'])\n\
             except Exception as x:\n    print(x, file=sys.stderr); sys.exit(1)\n"
        ));
        o.status
            .success()
            .then(|| String::from_utf8_lossy(&o.stdout).trim().to_string())
    }

    /// One unsigned request to this server (moto answers them on buckets, not on objects;
    /// boto3 costs a Python start per call): the status and the body.
    fn raw(&self, method: &str, target: &str) -> (u16, Vec<u8>) {
        use std::io::{Read, Write};
        let host = self.endpoint.trim_start_matches("http://");
        let mut c = std::net::TcpStream::connect(host).unwrap();
        write!(
            c,
            "{method} {target} HTTP/1.1\r\nHost: {host}\r\nContent-Length: 0\r\n\
             Connection: close\r\n\r\n"
        )
        .unwrap();
        let mut answer = Vec::new();
        c.read_to_end(&mut answer).unwrap();
        let head_end = answer
            .windows(4)
            .position(|w| w == b"\r\n\r\n")
            .map_or(answer.len(), |p| p + 4);
        let head = String::from_utf8_lossy(&answer[..head_end]).to_string();
        assert!(
            !head
                .to_ascii_lowercase()
                .contains("transfer-encoding: chunked"),
            "moto answered in chunks: {head}"
        );
        let status = head
            .split(' ')
            .nth(1)
            .and_then(|c| c.parse().ok())
            .unwrap_or(0);
        (status, answer[head_end..].to_vec())
    }

    /// Makes the bucket `bucket` (an unsigned request: no Python start).
    pub fn bucket(&self, bucket: &str) {
        let (status, body) = self.raw("PUT", &format!("/{bucket}"));
        assert_eq!(status, 200, "{}", String::from_utf8_lossy(&body));
    }

    /// The keys of `bucket` under `prefix`, sorted (an unsigned ListObjectsV2).
    pub fn keys(&self, bucket: &str, prefix: &str) -> Vec<String> {
        let (status, body) = self.raw("GET", &format!("/{bucket}?list-type=2&prefix={prefix}"));
        let body = String::from_utf8_lossy(&body);
        assert_eq!(status, 200, "{body}");
        let mut keys: Vec<String> = body
            .split("<Key>")
            .skip(1)
            .filter_map(|k| k.split_once("</Key>").map(|(k, _)| k.to_string()))
            .collect();
        keys.sort();
        keys
    }

    /// Deletes `s3://bucket/key`, with boto3 (moto refuses unsigned requests on objects).
    pub fn delete(&self, bucket: &str, key: &str) {
        let o = self.boto(&format!(
            "s3.delete_object(Bucket='{bucket}', Key='{key}')\n"
        ));
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }

    /// The multipart uploads of `bucket` begun and neither completed nor aborted.
    pub fn pending_uploads(&self, bucket: &str) -> usize {
        let o = self.boto(&format!(
            "print(len(s3.list_multipart_uploads(Bucket='{bucket}').get('Uploads', [])))\n"
        ));
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout).trim().parse().unwrap()
    }

    /// The environment a run needs to reach this server with the tests' credentials.
    pub fn env(&self) -> [(&'static str, String); 4] {
        [
            ("AWS_ENDPOINT_URL", self.endpoint.clone()),
            ("AWS_ACCESS_KEY_ID", KEY.to_string()),
            ("AWS_SECRET_ACCESS_KEY", SECRET.to_string()),
            ("AWS_REGION", "us-east-1".to_string()),
        ]
    }
}

impl Drop for Moto {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// What the fault server does wrong.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fault {
    /// Nothing: ranges, ETag, If-Match as a good server.
    None,
    /// Requests 1 to `n` (after the first, which learns the size) close the connection halfway
    /// through a body of more than 1 KiB.
    DropMidBody(usize),
    /// The first `n` requests get `503 Service Unavailable`.
    Unavailable(usize),
    /// The first `n` requests (the first tells the object's size) get no answer: the
    /// connection stays open, silent, for a minute.
    SilentHead(usize),
    /// Requests 1 to `n` (after the first) get their head and half their body, then nothing
    /// more for a minute.
    SilentBody(usize),
    /// After `n` requests the object is replaced by another version (another ETag); If-Match
    /// is honoured (412) when `if_match`, else ignored (the new ETag comes back).
    Replace { after: usize, if_match: bool },
    /// Every answer is `200` with the whole body.
    IgnoreRange,
    /// After the first request, ranges start one byte later than asked (and say so in their
    /// `Content-Range`).
    WrongRange,
}

/// How long a silent fault keeps its connection open without a byte.
const SILENCE: std::time::Duration = std::time::Duration::from_secs(60);

/// A tiny HTTP/1.1 server of one object, with a chosen [`Fault`]; runs until the test ends.
pub struct FaultServer {
    pub port: u16,
    pub requests: Arc<AtomicUsize>,
}

impl FaultServer {
    /// Serves `body` at `/NAME` (any path).
    pub fn start(body: Vec<u8>, fault: Fault) -> FaultServer {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let port = listener.local_addr().unwrap().port();
        let requests = Arc::new(AtomicUsize::new(0));
        let (count, body) = (requests.clone(), Arc::new(body));
        std::thread::spawn(move || {
            for stream in listener.incoming().flatten() {
                let (count, body) = (count.clone(), body.clone());
                std::thread::spawn(move || serve(stream, &body, fault, &count));
            }
        });
        FaultServer { port, requests }
    }

    pub fn url(&self, name: &str) -> String {
        format!("http://127.0.0.1:{}/{name}", self.port)
    }
}

/// A request's line and its headers (names in lower case, values trimmed); `None` once the
/// client has closed the connection.
fn read_request(read: &mut BufReader<TcpStream>) -> Option<(String, Vec<(String, String)>)> {
    let mut line = String::new();
    if read.read_line(&mut line).unwrap_or(0) == 0 {
        return None;
    }
    let mut headers = Vec::new();
    loop {
        let mut h = String::new();
        if read.read_line(&mut h).unwrap_or(0) == 0 {
            return None;
        }
        let h = h.trim_end();
        if h.is_empty() {
            return Some((line, headers));
        }
        let (k, v) = h.split_once(':').unwrap_or((h, ""));
        headers.push((k.to_ascii_lowercase(), v.trim().to_string()));
    }
}

fn serve(stream: TcpStream, body: &[u8], fault: Fault, count: &AtomicUsize) {
    let mut read = BufReader::new(stream.try_clone().unwrap());
    let mut out = stream;
    loop {
        let Some((_, headers)) = read_request(&mut read) else {
            return;
        };
        let header = |name: &str| headers.iter().find(|h| h.0 == name).map(|h| h.1.clone());
        let (range, if_match) = (header("range"), header("if-match"));
        let n = count.fetch_add(1, Ordering::SeqCst);
        // The object as it is now: the second version is the first with its last byte changed.
        let replaced = matches!(fault, Fault::Replace { after, .. } if n >= after);
        let mut object = body.to_vec();
        if replaced && let Some(b) = object.last_mut() {
            *b ^= 0xff;
        }
        let etag = if replaced { "\"v2\"" } else { "\"v1\"" };
        if matches!(fault, Fault::Unavailable(k) if n < k) {
            let _ = out.write_all(
                b"HTTP/1.1 503 Service Unavailable\r\nContent-Length: 0\r\nRetry-After: 0\r\n\r\n",
            );
            continue;
        }
        if matches!(fault, Fault::Replace { if_match: true, .. })
            && if_match.as_deref().is_some_and(|m| m != etag)
        {
            let _ = out.write_all(b"HTTP/1.1 412 Precondition Failed\r\nContent-Length: 0\r\n\r\n");
            continue;
        }
        let len = object.len() as u64;
        let asked = range.filter(|_| fault != Fault::IgnoreRange).and_then(|r| {
            let (a, b) = r.strip_prefix("bytes=")?.split_once('-')?;
            Some((a.parse::<u64>().ok()?, b.parse::<u64>().ok()?.min(len - 1)))
        });
        let asked = asked.map(|(a, b)| match fault {
            Fault::WrongRange if n > 0 && b + 1 < len => (a + 1, b + 1),
            _ => (a, b),
        });
        let (head, part) = match asked {
            Some((a, b)) => (
                format!(
                    "HTTP/1.1 206 Partial Content\r\nContent-Range: bytes {a}-{b}/{len}\r\n\
                     Content-Length: {}\r\nETag: {etag}\r\n\r\n",
                    b - a + 1
                ),
                &object[a as usize..=b as usize],
            ),
            None => (
                format!("HTTP/1.1 200 OK\r\nContent-Length: {len}\r\nETag: {etag}\r\n\r\n"),
                &object[..],
            ),
        };
        if matches!(fault, Fault::SilentHead(k) if n < k) {
            std::thread::sleep(SILENCE);
            return;
        }
        if out.write_all(head.as_bytes()).is_err() {
            return;
        }
        if matches!(fault, Fault::SilentBody(k) if (1..=k).contains(&n)) {
            let _ = out.write_all(&part[..part.len() / 2]);
            let _ = out.flush();
            std::thread::sleep(SILENCE);
            return;
        }
        if matches!(fault, Fault::DropMidBody(k) if part.len() > 1024 && (1..=k).contains(&n)) {
            let _ = out.write_all(&part[..part.len() / 2]);
            return; // the connection drops
        }
        if out.write_all(part).is_err() {
            return;
        }
    }
}

/// A copy of `files` in a fresh folder (what nginx serves).
pub fn served(files: &[&Path]) -> (tempfile::TempDir, Vec<String>) {
    let dir = tempfile::tempdir().unwrap();
    let names = files
        .iter()
        .map(|f| {
            let name = f.file_name().unwrap().to_string_lossy().to_string();
            std::fs::copy(f, dir.path().join(&name)).unwrap();
            name
        })
        .collect();
    (dir, names)
}

/// The bytes of a file, to serve.
pub fn bytes(p: &PathBuf) -> Vec<u8> {
    let mut v = Vec::new();
    std::fs::File::open(p).unwrap().read_to_end(&mut v).unwrap();
    v
}

/// A tiny S3 endpoint that takes multipart uploads and falls silent at one part, to interrupt
/// an upload midway: `HEAD` of a bucket is 200; `POST …?uploads` starts upload `up1`; parts
/// are read and stored (ETag `"pN"`) except part `silent`, whose answer never comes; every
/// request's line (method and target) is logged in [`FakeS3::log`].
pub struct FakeS3 {
    pub port: u16,
    pub log: Arc<std::sync::Mutex<Vec<String>>>,
}

impl FakeS3 {
    pub fn start(silent: u16) -> FakeS3 {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let port = listener.local_addr().unwrap().port();
        let log = Arc::new(std::sync::Mutex::new(Vec::new()));
        let all = log.clone();
        std::thread::spawn(move || {
            for stream in listener.incoming().flatten() {
                let log = all.clone();
                std::thread::spawn(move || serve_s3(stream, silent, &log));
            }
        });
        FakeS3 { port, log }
    }

    pub fn endpoint(&self) -> String {
        format!("http://127.0.0.1:{}", self.port)
    }

    /// The request lines received so far.
    pub fn requests(&self) -> Vec<String> {
        self.log.lock().unwrap().clone()
    }
}

fn serve_s3(stream: TcpStream, silent: u16, log: &std::sync::Mutex<Vec<String>>) {
    let mut read = BufReader::new(stream.try_clone().unwrap());
    let mut out = stream;
    loop {
        let Some((line, headers)) = read_request(&mut read) else {
            return;
        };
        let length: usize = headers
            .iter()
            .find(|h| h.0 == "content-length")
            .map_or(0, |h| h.1.parse().unwrap_or(0));
        let mut body = vec![0u8; length];
        if read.read_exact(&mut body).is_err() {
            return;
        }
        let mut words = line.split_whitespace();
        let (method, target) = (words.next().unwrap_or(""), words.next().unwrap_or(""));
        // Without the signature's parameters.
        let (path, query) = target.split_once('?').unwrap_or((target, ""));
        let query: Vec<&str> = query
            .split('&')
            .filter(|q| !q.starts_with("X-Amz-"))
            .collect();
        log.lock()
            .unwrap()
            .push(format!("{method} {path}?{}", query.join("&")));
        let part: Option<u16> = target
            .split(['?', '&'])
            .find_map(|q| q.strip_prefix("partNumber=")?.parse().ok());
        let answer = match (method, part) {
            ("PUT", Some(n)) if n == silent => {
                std::thread::sleep(SILENCE);
                return;
            }
            ("PUT", Some(n)) => {
                format!("HTTP/1.1 200 OK\r\nETag: \"p{n}\"\r\nContent-Length: 0\r\n\r\n")
            }
            ("POST", _) if target.contains("uploads") => {
                let xml = "<InitiateMultipartUploadResult><UploadId>up1</UploadId>\
                           </InitiateMultipartUploadResult>";
                format!(
                    "HTTP/1.1 200 OK\r\nContent-Length: {}\r\n\r\n{xml}",
                    xml.len()
                )
            }
            ("DELETE", _) => "HTTP/1.1 204 No Content\r\n\r\n".to_string(),
            _ => "HTTP/1.1 200 OK\r\nContent-Length: 0\r\n\r\n".to_string(),
        };
        if out.write_all(answer.as_bytes()).is_err() {
            return;
        }
    }
}
