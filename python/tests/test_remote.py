"""Remote inputs from Python: an ``s3://`` URL (moto's S3 server, started here) gives the local
file's bytes, and a missing object raises naming its URL (docs/REMOTE.md)."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import time

import pytest

import sweeptin

from conftest import data, missing

KEY, SECRET = "testkey", "testsecret"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def s3(monkeypatch):
    """moto's S3 server in its own process (an in-process server would wait for this
    process's own requests, and its shutdown for the extension's pooled connection), with a
    bucket ``lidar``; the AWS variables the library reads point at it."""
    try:
        import boto3
    except ImportError:
        missing("boto3")
    exe = shutil.which("moto_server")
    if exe is None:
        missing("moto_server (moto[server])")
    port = free_port()
    server = subprocess.Popen(
        [exe, "-H", "127.0.0.1", "-p", str(port)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        endpoint = f"http://127.0.0.1:{port}"
        for _ in range(300):
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                time.sleep(0.1)
        client = boto3.client(
            "s3",
            endpoint_url=endpoint,
            aws_access_key_id=KEY,
            aws_secret_access_key=SECRET,
            region_name="us-east-1",
        )
        client.create_bucket(Bucket="lidar")
        for k, v in {
            "AWS_ENDPOINT_URL": endpoint,
            "AWS_ACCESS_KEY_ID": KEY,
            "AWS_SECRET_ACCESS_KEY": SECRET,
            "AWS_REGION": "us-east-1",
        }.items():
            monkeypatch.setenv(k, v)
        for k in ("AWS_PROFILE", "AWS_SESSION_TOKEN", "AWS_NO_SIGN_REQUEST"):
            monkeypatch.delenv(k, raising=False)
        yield client
    finally:
        server.kill()
        server.wait()


def test_dem_of_an_s3_object_is_the_local_files(s3, tmp_path):
    local = data("lidar/startinpy_small.laz")
    s3.upload_file(os.fspath(local), "lidar", "tiles/small.laz")
    a, b = tmp_path / "local.tif", tmp_path / "remote.tif"
    sa = sweeptin.dem(local, a, cell=1, classes=[2])
    sb = sweeptin.dem("s3://lidar/tiles/small.laz", b, cell=1, classes=[2])
    assert a.read_bytes() == b.read_bytes()
    assert sa["run"]["points_read"] == sb["run"]["points_read"] == 18392


def test_a_missing_s3_object_raises_naming_it_and_writes_nothing(s3, tmp_path):
    out = tmp_path / "m.tif"
    with pytest.raises(sweeptin.SweeptinError, match="s3://lidar/none.laz"):
        sweeptin.dem("s3://lidar/none.laz", out, cell=1)
    assert not out.exists()


def test_a_plan_on_s3_over_an_s3_input_merges_to_the_local_plans_mosaic(s3, tmp_path):
    local = data("lidar/startinpy_small.laz")
    # A name no other test opened: a process keeps the first version of each remote object it
    # opens (and where it was found).
    s3.upload_file(os.fspath(local), "lidar", "plan/small.laz")
    want, got = tmp_path / "want.tif", tmp_path / "got.tif"
    p = sweeptin.plan("dem", local, tmp_path / "job", tile=25, cell=1)
    for i in p.tasks:
        sweeptin.run_task(p, i)
    sweeptin.merge(p, want)
    q = sweeptin.plan("dem", "s3://lidar/plan/small.laz", "s3://lidar/job/", tile=25, cell=1)
    assert q.path.startswith("s3://lidar/job/") and len(q) == len(p)
    for i in q.tasks:
        assert sweeptin.run_task(q, i)["status"] in ("done", "empty")
    sweeptin.merge(q, got)
    assert got.read_bytes() == want.read_bytes()
    assert not (tmp_path / "s3:").exists()


def test_a_dem_written_to_s3_is_the_local_files_bytes(s3, tmp_path):
    local = data("lidar/startinpy_small.laz")
    want = tmp_path / "want.tif"
    sweeptin.dem(local, want, cell=1, classes=[2])
    sweeptin.dem(local, "s3://lidar/out/dem.tif", cell=1, classes=[2])
    body = s3.get_object(Bucket="lidar", Key="out/dem.tif")["Body"].read()
    assert body == want.read_bytes()
    assert not (tmp_path / "s3:").exists() and not os.path.exists("s3:")
