"""Load: 100 concurrent uploads of a small submission from one client process on loopback, while another thread
times a status call. Every upload is answered (accepted or refused by the quota), none is lost, and the p95
latency of the status call is printed (docs/challenge.md records it)."""

from __future__ import annotations

import threading
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from ch_server import RANDOM_AGENT, Server, add_team, make_challenge, policy_folder

from main_bench.challenge.client import pack

UPLOADS = 100
QUOTA = 20


@pytest.mark.slow
def test_100_concurrent_uploads_keep_the_api_responsive(tmp_path, ch_dataset):
    dataset, cache = ch_dataset
    root = tmp_path / "challenge"
    make_challenge(root, dataset, cache, "--quota", QUOTA)
    token = add_team(root, "loaders")
    data = pack(policy_folder(tmp_path / "agent", RANDOM_AGENT))
    server = Server(root).start()
    try:
        status, first = server.call("POST", "/api/submissions?phase=val&mode=silent", token, data)
        assert status == 202, first
        latencies: list[float] = []
        done = threading.Event()

        def poll() -> None:
            while not done.is_set():
                t0 = time.perf_counter()
                status, doc = server.call("GET", f"/api/submissions/{first['id']}", token)
                latencies.append(time.perf_counter() - t0)
                assert status == 200, doc
                time.sleep(0.01)

        poller = threading.Thread(target=poll)
        poller.start()
        t0 = time.perf_counter()
        with ThreadPoolExecutor(max_workers=UPLOADS) as pool:
            answers = list(pool.map(lambda _: server.call("POST", "/api/submissions?phase=val&mode=silent", token,
                                                          data, timeout=120), range(UPLOADS)))
        seconds = time.perf_counter() - t0
        done.set()
        poller.join(timeout=60)
        statuses = [s for s, _ in answers]
        accepted = sorted(doc["id"] for s, doc in answers if s == 202)
        assert set(statuses) <= {202, 429}, [a for a in answers if a[0] not in (202, 429)][:3]
        assert len(accepted) == QUOTA - 1 and statuses.count(429) == UPLOADS - QUOTA + 1
        assert all("quota reached" in doc["error"] for s, doc in answers if s == 429)
        listed = server.call("GET", "/api/submissions", token)[1]["submissions"]
        assert [s["id"] for s in listed] == sorted([first["id"], *accepted])  # none lost, none extra
        assert list((root / "uploads").iterdir()) == []
        p50, p95 = np.percentile(latencies, [50, 95])
        print(f"\n{UPLOADS} uploads in {seconds:.2f} s; status call under load: {len(latencies)} calls, "
              f"p50 {1000 * p50:.1f} ms, p95 {1000 * p95:.1f} ms, max {1000 * max(latencies):.1f} ms")
        assert len(latencies) >= 5 and p95 < 5.0
    finally:
        server.stop()
