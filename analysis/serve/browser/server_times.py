"""Server time of each `twv serve` endpoint for the default vehicle (what the README quotes):
each request 30 times, median and max of the `server_ms` the server reports.

    python3 analysis/serve/browser/server_times.py http://127.0.0.1:8040
"""

import json
import math
import statistics
import sys
import urllib.request


def post(base: str, path: str, body: dict) -> float:
    request = urllib.request.Request(
        base.rstrip("/") + path,
        data=json.dumps(body).encode(),
        headers={"Content-Type": "application/json"},
    )
    with urllib.request.urlopen(request) as answer:
        return json.load(answer)["server_ms"]


def main(base: str) -> None:
    gains = {"kp": 3860, "ki": 0, "kd": 1980}
    controller = {"pitch": {"gains": gains}}
    tilt = 0.1
    metric = {"h": 1e-3, "t_sample": 0.1, "iterations": 30, "transient": 0.5}
    metric |= {"t_end": 10, "sample": 0.01, "fall_angle": math.pi / 2}
    row = {
        "kp": {"lo": 200, "hi": 9800, "n": 20},
        "kd": {"lo": 1900, "hi": 1900, "n": 1},
    }
    jobs = {
        "simulate": ("/api/simulate", {"controller": controller, "phi0": tilt}),
        "margins (300 frequencies)": (
            "/api/linearize",
            {"gains": gains, "frequency_points": 300},
        ),
        "exponent": ("/api/exponent", {"controller": controller, "tilt": tilt}),
        "phase (4 tilts)": (
            "/api/phase",
            {
                "portraits": [["current gains", {"closed": controller}]],
                "tilts": [tilt, -tilt, 2 * tilt, -2 * tilt],
            },
        ),
        "tune": ("/api/tune", {"spec": "dpm>=45", "tilt": tilt}),
        "map row (20 points)": (
            "/api/sweep",
            {
                "grid": row,
                "metric": "max-lyapunov",
                "tilt": tilt,
                "controller": controller,
                "metric_settings": metric,
            },
        ),
    }
    for name, (path, settings) in jobs.items():
        times = [post(base, path, {"settings": settings}) for _ in range(30)]
        print(
            f"{name:26s} median {statistics.median(times):7.2f} ms   max {max(times):7.2f} ms"
        )


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "http://127.0.0.1:8040")
