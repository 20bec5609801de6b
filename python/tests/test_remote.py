"""Remote inputs from Python: an ``s3://`` URL (moto's S3 server, started here) gives the local
file's bytes, and a missing object raises naming its URL (docs/REMOTE.md)."""

from __future__ import annotations

import os

import pytest

import sweeptin

from conftest import data, missing

KEY, SECRET = "testkey", "testsecret"


@pytest.fixture
def s3(monkeypatch):
    """An S3 endpoint with bucket ``lidar``; the AWS variables the library reads point at it."""
    try:
        import boto3
        from moto.server import ThreadedMotoServer
    except ImportError:
        missing("moto[server] and boto3")
    server = ThreadedMotoServer(ip_address="127.0.0.1", port=0, verbose=False)
    server.start()
    try:
        host, port = server.get_host_and_port()
        endpoint = f"http://{host}:{port}"
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
        server.stop()


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
