"""The live page of `twv serve` in a real browser: Debian's chromium, headless, driven through
chromium-driver (WebDriver) by selenium. A server started here serves the page; the test moves
the Kp slider with the pointer, waits for the redraw, and checks that the plotted recovery and
the printed margins are the library's for the new gains — computed independently by the `twv`
binary's CLI (`twv linear --json`, `twv sim --out`). A screenshot is kept as an artefact
(target/browser/, or $TWV_ARTEFACTS).

Needs /usr/bin/chromium and /usr/bin/chromedriver: the README's test command installs them
(apt packages chromium and chromium-driver). Without them this test fails; it is not skipped.
"""

from __future__ import annotations

import csv
import json
import math
import os
import subprocess
import time
from pathlib import Path

import pytest
from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.keys import Keys

ROOT = Path(__file__).resolve().parents[3]
TWV = Path(os.environ.get("TWV_BIN", ROOT / "target" / "debug" / "twv"))
ARTEFACTS = Path(os.environ.get("TWV_ARTEFACTS", ROOT / "target" / "browser"))
CHROMIUM = Path("/usr/bin/chromium")
CHROMEDRIVER = Path("/usr/bin/chromedriver")


def twv(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [str(TWV), *args], capture_output=True, text=True, timeout=120, check=False
    )


@pytest.fixture(scope="module")
def server():
    assert TWV.exists(), f"{TWV}: build the twv binary first (cargo build -p twv-cli)"
    proc = subprocess.Popen(
        [str(TWV), "serve", "--port", "0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    line = proc.stdout.readline()
    assert line.startswith("twv serve: http://127.0.0.1:"), line + proc.stderr.read()
    url = line.split()[2]
    yield url
    proc.terminate()
    proc.wait(timeout=10)


@pytest.fixture(scope="module")
def browser():
    for path in (CHROMIUM, CHROMEDRIVER):
        assert path.exists(), (
            f"{path} missing: apt-get install chromium chromium-driver"
        )
    options = webdriver.ChromeOptions()
    options.binary_location = str(CHROMIUM)
    for arg in (
        "--headless=new",
        "--no-sandbox",
        "--disable-dev-shm-usage",
        "--window-size=1500,2000",
    ):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service(str(CHROMEDRIVER)), options=options)
    yield driver
    driver.quit()


def wait_for(driver, script: str, timeout: float = 30.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = driver.execute_script(script)
        if value:
            return value
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting for: {script}")


def shown(driver, element_id: str) -> float:
    return float(driver.find_element("id", element_id).get_attribute("data-value"))


def cli_margins(kp: float, ki: float, kd: float) -> dict:
    out = twv("linear", "--json", "--gains", f"{kp!r},{ki!r},{kd!r}")
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)["pitch"]["margins"]


def cli_phi(tmp: Path, kp: float, ki: float, kd: float, tilt: float) -> list[float]:
    out = twv(
        "sim",
        "--gains",
        f"{kp!r},{ki!r},{kd!r}",
        "--tilt",
        repr(tilt),
        "--out",
        str(tmp),
    )
    assert out.returncode == 0, out.stderr
    with open(tmp / "sim.csv", newline="") as f:
        return [float(row["phi"]) for row in csv.DictReader(f)]


def page_state(driver) -> dict:
    return driver.execute_script(
        """
        const t = window.twv;
        return {
          updates: t.updates, errors: t.errors, gains: t.gains,
          tilt: Number(document.getElementById('tilt-num').value),
          phi: t.charts['c-phi'].data.datasets[0].data.map(p => p.y),
          timing: t.timing,
        };
        """
    )


def check_against_cli(driver, tmp: Path) -> dict:
    state = page_state(driver)
    assert not state["errors"], state["errors"]
    g = state["gains"]
    margins = cli_margins(g["kp"], g["ki"], g["kd"])
    assert shown(driver, "pm") == margins["phase_margin"]["deg"]
    assert shown(driver, "gm") == margins["gain_margin_lower"]
    assert shown(driver, "dm") == margins["delay_margin"]
    assert shown(driver, "disk") == margins["disk_alpha"]
    phi = cli_phi(tmp, g["kp"], g["ki"], g["kd"], state["tilt"])
    assert state["phi"] == phi, "the plotted recovery is not the CLI's"
    state["phase_margin"] = margins["phase_margin"]["deg"]
    return state


def test_moving_the_kp_slider_redraws_with_the_librarys_numbers(
    server, browser, tmp_path
):
    browser.get(server)
    wait_for(browser, "return window.twv && window.twv.updates >= 1")
    before = check_against_cli(browser, tmp_path / "before")
    assert before["gains"] == {"kp": 3860, "ki": 0, "kd": 1980}

    slider = browser.find_element("id", "kp")
    updates = before["updates"]
    # A real pointer drag of the thumb to the left: Kp falls.
    ActionChains(browser).click_and_hold(slider).move_by_offset(
        -70, 0
    ).release().perform()
    wait_for(
        browser, f"return window.twv.updates > {updates} && window.twv.gains.kp != 3860"
    )
    # Let a redraw queued by the last pointer event finish.
    time.sleep(0.5)
    wait_for(
        browser,
        "return window.twv.gains.kp == Number(document.getElementById('kp').value)",
    )
    after = check_against_cli(browser, tmp_path / "after")
    assert after["gains"]["kp"] < 3860
    assert after["phi"] != before["phi"]
    assert after["phase_margin"] != before["phase_margin"]

    ARTEFACTS.mkdir(parents=True, exist_ok=True)
    browser.save_screenshot(str(ARTEFACTS / "serve-page.png"))
    print(f"server time per request [ms]: {after['timing']}; screenshot in {ARTEFACTS}")


def test_an_impossible_parameter_is_named_beside_its_field_and_nothing_breaks(
    server, browser
):
    browser.get(server)
    wait_for(browser, "return window.twv && window.twv.updates >= 1")
    updates = browser.execute_script("return window.twv.updates")
    browser.execute_script(
        "const f = document.getElementById('param-I2_xx'); f.value = '-1';"
        "f.dispatchEvent(new Event('change'));"
    )
    wait_for(browser, f"return window.twv.updates > {updates}")
    message = browser.find_element("id", "err-I2_xx").text
    assert "`I2_xx`" in message and "positive" in message, message
    assert browser.find_element("id", "error").is_displayed()
    # Fixed again: the error goes, the plots redraw.
    updates = browser.execute_script("return window.twv.updates")
    browser.execute_script(
        "const f = document.getElementById('param-I2_xx'); f.value = '0.81';"
        "f.dispatchEvent(new Event('change'));"
    )
    wait_for(browser, f"return window.twv.updates > {updates}")
    assert browser.find_element("id", "err-I2_xx").text == ""
    assert not browser.execute_script("return window.twv.errors.length")


def test_tune_moves_the_sliders_to_the_certificate(server, browser):
    browser.get(server)
    wait_for(browser, "return window.twv && window.twv.updates >= 1")
    browser.find_element("id", "tune").click()
    tuned = wait_for(browser, "return window.twv.tuned")
    out = twv("tune", "--json")
    assert out.returncode == 0, out.stderr
    certificate = json.loads(out.stdout)["result"]["certificate"]["gains"]
    assert tuned == certificate
    # The sliders moved to the certificate (to their 10-unit steps) and the page redrew there.
    for name in ("kp", "kd"):
        value = float(
            browser.execute_script(f"return document.getElementById('{name}').value")
        )
        assert math.isclose(value, certificate[name], abs_tol=5.0), (
            name,
            value,
            certificate,
        )
    wait_for(
        browser,
        "return window.twv.gains.kd == Number(document.getElementById('kd').value)",
    )


def test_certified_gains_beyond_a_slider_widen_it_instead_of_being_clamped(
    server, browser
):
    """dpm>=80 certifies Kp ≈ 13 900, beyond the Kp slider's 10 000 (issue 38: the page used to
    show the clamped 10 000 beside a 'met' verdict)."""
    browser.get(server)
    wait_for(browser, "return window.twv && window.twv.updates >= 1")
    browser.execute_script("document.getElementById('spec').value = 'dpm>=80';")
    browser.find_element("id", "tune").click()
    tuned = wait_for(browser, "return window.twv.tuned")
    out = twv("tune", "--spec", "dpm>=80", "--json")
    assert out.returncode == 0, out.stderr
    certificate = json.loads(out.stdout)["result"]["certificate"]["gains"]
    assert tuned == certificate
    assert certificate["kp"] > 10_000
    kp = browser.find_element("id", "kp")
    assert float(kp.get_attribute("max")) >= certificate["kp"]
    # To the slider's 10-unit step.
    assert math.isclose(
        float(kp.get_attribute("value")), certificate["kp"], abs_tol=10.0
    )
    assert "slider range widened: kp" in browser.find_element("id", "tune-status").text


SIZES = {"phone": (390, 844), "desktop": (1400, 1000)}


@pytest.mark.parametrize("size", SIZES)
def test_the_page_reads_well_on_a_phone_and_a_desktop(server, browser, size, tmp_path):
    """At 390 x 844 (a phone) and 1400 x 1000: no horizontal overflow, every plot at least 300 px
    wide on the phone, the study's tilt settable exactly (0.1 rad) with the CLI's peak force, the
    map with its colour bar, Nyquist with equal axes, no label that needs a combining dot."""
    width, height = SIZES[size]
    browser.set_window_size(width, height)
    browser.get(server)
    wait_for(browser, "return window.twv && window.twv.updates >= 1")
    inner = browser.execute_script("return window.innerWidth")
    scroll = browser.execute_script("return document.documentElement.scrollWidth")
    assert scroll <= inner, (
        f"{size}: the page is {scroll} px wide in a {inner} px window"
    )
    widths = browser.execute_script(
        "return [...document.querySelectorAll('.plots canvas')]"
        ".map(c => [c.id, c.getBoundingClientRect().width]);"
    )
    assert len(widths) >= 10
    for name, w in widths:
        assert w >= 300, f"{size}: {name} is {w:.0f} px wide"
        assert w <= inner, f"{size}: {name} is wider than the window"

    # The study's tilt, exactly: 0.1 rad in the field, the CLI's peak force for it.
    updates = browser.execute_script("return window.twv.updates")
    browser.execute_script(
        "const f = document.getElementById('tilt-num'); f.value = '0.1';"
        "f.dispatchEvent(new Event('change'));"
    )
    wait_for(browser, f"return window.twv.updates > {updates}")
    state = browser.execute_script(
        "return {tilt: Number(document.getElementById('tilt-num').value),"
        " force: window.twv.last.simulate.result.metrics.peak_force,"
        " shown: document.getElementById('peak-force').textContent,"
        " degrees: document.getElementById('tilt-deg').textContent, gains: window.twv.gains};"
    )
    assert state["tilt"] == 0.1
    g = state["gains"]
    out = twv(
        "sim",
        "--json",
        "--tilt",
        "0.1",
        "--gains",
        f"{g['kp']!r},{g['ki']!r},{g['kd']!r}",
    )
    assert out.returncode == 0, out.stderr
    cli = json.loads(out.stdout)["metrics"]["peak_force"]
    assert state["force"] == cli, (state, cli)
    # Shown as the page formats it (4 significant digits, like JavaScript's toPrecision).
    assert state["shown"] == f"{cli:.4g} N", (state, cli)
    assert state["degrees"] == "(5.73°)", state

    # Equal axes on the Nyquist plot: one unit as many pixels across as up.
    px = browser.execute_script(
        "const c = window.twv.charts['c-nyquist'];"
        "return [c.scales.x.getPixelForValue(1) - c.scales.x.getPixelForValue(0),"
        " c.scales.y.getPixelForValue(0) - c.scales.y.getPixelForValue(1)];"
    )
    assert abs(px[0] - px[1]) <= 0.02 * px[0], px

    # Labels the fonts surely have: no combining dot (it was lost, reading Φ̇ as Φ).
    texts = browser.execute_script(
        "return Object.values(window.twv.charts).flatMap(c => [c.options.plugins.title.text,"
        " c.options.scales.x.title.text, c.options.scales.y.title.text,"
        " ...c.data.datasets.map(d => d.label)]).concat([document.body.innerText]);"
    )
    assert not any("\u0307" in t for t in texts), [t for t in texts if "\u0307" in t]

    # The map with its colour bar: red at the top (λ1 > 0), blue at the bottom.
    browser.find_element("id", "map").click()
    wait_for(
        browser,
        "return window.twv.mapColorBar && "
        "document.getElementById('map-progress').value == 1",
        timeout=120,
    )
    bar = browser.execute_script(
        "const c = document.getElementById('c-map'), b = window.twv.mapColorBar;"
        "const r = window.devicePixelRatio || 1, g = c.getContext('2d');"
        "const at = (y) => Array.from(g.getImageData((b.x + b.width / 2) * r, y * r, 1, 1).data);"
        "return {top: at(12), bottom: at(c.clientHeight - 50), min: b.min, max: b.max,"
        " width: c.getBoundingClientRect().width};"
    )
    assert bar["min"] < 0 < bar["max"], bar
    assert bar["top"][0] > bar["top"][2] and bar["bottom"][2] > bar["bottom"][0], bar
    assert bar["width"] >= 300, bar

    ARTEFACTS.mkdir(parents=True, exist_ok=True)
    browser.save_screenshot(str(ARTEFACTS / f"serve-page-{size}.png"))
    browser.set_window_size(1500, 2000)


@pytest.fixture(scope="module")
def bicycle_server():
    """`twv serve --model whipple`: a model with a steer input, whose page is /bicycle."""
    proc = subprocess.Popen(
        [str(TWV), "serve", "--model", "whipple", "--port", "0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    line = proc.stdout.readline()
    assert line.startswith("twv serve: http://127.0.0.1:"), line + proc.stderr.read()
    yield line.split()[2]
    proc.terminate()
    proc.wait(timeout=10)


def bicycle_state(driver) -> dict:
    return driver.execute_script(
        """
        const t = window.twv;
        return {
          updates: t.updates, errors: t.errors, gains: t.gains, speed: t.speed,
          filter: t.filter,
          path: location.pathname,
          push: Number(document.getElementById('push').value),
          t_end: Number(document.getElementById('t-end').value),
          lean: t.charts['c-lean'].data.datasets[0].data.map(p => p.y),
          verdict: document.getElementById('loop-verdict').dataset.verdict,
          ride: document.getElementById('ride-verdict').dataset.verdict,
        };
        """
    )


def bicycle_against_cli(driver, tmp: Path) -> dict:
    """The page's steer-loop verdict and margins are `twv linearize --speed --steer-gains`'s and
    its plotted lean is `twv ride`'s, for the gains and speed the page shows."""
    state = bicycle_state(driver)
    assert not state["errors"], state["errors"]
    g = state["gains"]
    law = ",".join(
        f"{k}={g[k]!r}" for k in ("k_phi", "k_delta", "k_phi_dot", "k_delta_dot")
    )
    common = (
        "--model",
        "whipple",
        "--speed",
        repr(state["speed"]),
        "--steer-gains",
        law,
    )
    if state["filter"] is not None:
        common += ("--steer-filter", repr(state["filter"]))
    out = twv("linearize", "--json", *common)
    assert out.returncode in (0, 3), out.stderr
    steer = json.loads(out.stdout)["steer"]
    assert state["verdict"] == (
        "stable" if steer["loop_poles"]["stable"] else "unstable"
    )
    m = steer["margins"]
    if m is None:
        assert driver.find_element("id", "disk").get_attribute("data-value") == ""
    else:
        assert shown(driver, "pm") == m["phase_margin"]["deg"]
        assert shown(driver, "disk") == m["disk_alpha"]
        assert shown(driver, "dm") == m["delay_margin"]
    ride = twv(
        "ride",
        *common,
        "--perturb",
        f"w_phi={state['push']!r}",
        "--t-end",
        repr(state["t_end"]),
        "--out",
        str(tmp),
    )
    assert ride.returncode in (0, 3), ride.stderr
    with open(tmp / "ride.csv", newline="") as f:
        lean = [float(row["phi"]) for row in csv.DictReader(f)]
    assert state["lean"] == lean, "the plotted lean is not the CLI's"
    return state


def test_the_bicycle_page_steers_as_the_cli_does(bicycle_server, browser, tmp_path):
    """The vehicle's page sends a model with a steer input to /bicycle; there, lean-rate
    feedback at 3 m/s balances the bicycle (a stable loop, the push recovered), and dragging the
    k_φ̇ slider down to weak feedback makes the loop unstable — each time with the CLI's
    numbers and the CLI's lean."""
    browser.get(bicycle_server)
    wait_for(browser, "return window.twv && window.twv.updates >= 1")
    before = bicycle_against_cli(browser, tmp_path / "before")
    assert before["path"] == "/bicycle"
    assert before["gains"]["k_phi_dot"] == 15 and before["speed"] == 3
    assert before["verdict"] == "stable" and before["ride"] == "recovered"
    slider = browser.find_element("id", "k_phi_dot")
    updates = before["updates"]
    # A real pointer drag of the thumb to the left: k_φ̇ falls below what 3 m/s needs.
    ActionChains(browser).click_and_hold(slider).move_by_offset(
        -60, 0
    ).release().perform()
    wait_for(
        browser,
        f"return window.twv.updates > {updates} && window.twv.gains.k_phi_dot < 5",
    )
    time.sleep(0.5)
    wait_for(
        browser,
        "return window.twv.gains.k_phi_dot == "
        "Number(document.getElementById('k_phi_dot').value)",
    )
    after = bicycle_against_cli(browser, tmp_path / "after")
    assert after["verdict"] == "unstable", after["gains"]
    assert after["lean"] != before["lean"]


def test_the_bicycle_pages_rate_filter_is_the_clis(bicycle_server, browser, tmp_path):
    """The lean-rate feedback that balances the bicycle at 3 m/s, read through a 50 ms rate
    filter, no longer does: the page's verdict flips with the CLI's (`--steer-filter 0.05`), and
    emptying the field reads the rates directly again."""
    browser.get(bicycle_server)
    wait_for(browser, "return window.twv && window.twv.updates >= 1")
    before = bicycle_against_cli(browser, tmp_path / "direct")
    assert before["filter"] is None and before["verdict"] == "stable", before
    field = browser.find_element("id", "filter")
    updates = before["updates"]
    field.send_keys("50", Keys.TAB)
    wait_for(
        browser, f"return window.twv.updates > {updates} && window.twv.filter === 0.05"
    )
    lagged = bicycle_against_cli(browser, tmp_path / "lagged")
    assert lagged["verdict"] == "unstable", lagged
    updates = lagged["updates"]
    field.send_keys(Keys.BACKSPACE, Keys.BACKSPACE, Keys.TAB)
    wait_for(
        browser, f"return window.twv.updates > {updates} && window.twv.filter === null"
    )
    again = bicycle_against_cli(browser, tmp_path / "again")
    assert again["verdict"] == "stable" and again["lean"] == before["lean"]
    ARTEFACTS.mkdir(parents=True, exist_ok=True)
    browser.save_screenshot(str(ARTEFACTS / "serve-bicycle.png"))
