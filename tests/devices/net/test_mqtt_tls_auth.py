"""A shared lab broker: TLS with a private CA and username/password; a refused login is reported, not raised."""
from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest
from mqtt_broker import MOSQUITTO, Broker, wait_until

from swarmdeck.devices.net.mqtt_config import parse_broker_url
from swarmdeck.devices.net.transport_mqtt import MqttTransport

pytestmark = pytest.mark.mqtt


def make_tls_broker(tmp: Path) -> Broker:
    if not (os.access(MOSQUITTO, os.X_OK) and shutil.which("openssl") and shutil.which("mosquitto_passwd")):
        pytest.skip("needs Debian's mosquitto (with mosquitto_passwd) and openssl")

    def run(*cmd: str) -> None:
        subprocess.run(cmd, cwd=tmp, check=True, capture_output=True)

    ec = ["-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes"]
    run("openssl", "req", "-x509", *ec, "-keyout", "ca.key", "-out", "ca.crt", "-days", "1", "-subj", "/CN=swarmdeck test CA")
    run("openssl", "req", *ec, "-keyout", "server.key", "-out", "server.csr", "-subj", "/CN=127.0.0.1")
    (tmp / "san.ext").write_text("subjectAltName=IP:127.0.0.1\n")
    run("openssl", "x509", "-req", "-in", "server.csr", "-CA", "ca.crt", "-CAkey", "ca.key", "-CAcreateserial",
        "-out", "server.crt", "-days", "1", "-extfile", "san.ext")
    run("mosquitto_passwd", "-b", "-c", "passwords", "lab", "s3cret")
    for f in ("server.key", "passwords"):
        os.chmod(tmp / f, 0o600)
    broker = Broker(tmp, listener_conf=(
        f"cafile {tmp / 'ca.crt'}\ncertfile {tmp / 'server.crt'}\nkeyfile {tmp / 'server.key'}\n"
        f"allow_anonymous false\npassword_file {tmp / 'passwords'}\n"))
    broker.start()
    return broker


def test_tls_with_credentials_and_a_refused_login(tmp_path):
    broker = make_tls_broker(tmp_path)
    ca = str(tmp_path / "ca.crt")
    good = bad = None
    try:
        good = MqttTransport(parse_broker_url(f"mqtts://lab:s3cret@127.0.0.1:{broker.port}", ca_certs=ca,
                                              protocol="5"), ids=[0]).start()
        assert good.link.wait_connected(10), good.status().state
        assert good.send([0], [0.1], [0.0])
        bad = MqttTransport(parse_broker_url(f"mqtts://lab:wrong@127.0.0.1:{broker.port}", ca_certs=ca), ids=[0]).start()
        wait_until(lambda: bad.counters.get("connect_refused") >= 1, 10, "refused login counted")
        st = bad.status()
        assert not st.connected and "refused the connection" in st.state
        assert bad.send([0], [0.1], [0.0]) is False and bad.status().counters["undeliverable"] == 1
    finally:
        for t in (good, bad):
            if t is not None:
                t.close()
        broker.stop()
