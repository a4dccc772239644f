#!/usr/bin/env python3
"""`portico dashboard` in a real headless browser (docs/dashboard.md).

Starts a coordinator, two workers and the dashboard on a generated demo
building, opens the printed URL in Debian's Chromium driven by Selenium, and
checks what a user sees: a job's progress advancing and its preview image
changing as render passes land, its priority changed from the page and a
second job cancelled from it (both confirmed by `portico status`), and requests without the token refused (401), with a
wrong one or a forged action refused (403).

    dashboard_test.py BIN_DIR [--screenshot FILE.png]

Exit status 77 (skipped) when Selenium, Chromium or chromedriver is missing
(deploy/install-deps.sh installs them).
"""
import argparse
import base64
import hashlib
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request

SKIP = 77


def find_browser():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


class Farm:
    """The processes of one test, stopped (and their logs shown on failure) at the end."""

    def __init__(self, bin_dir, work):
        self.bin, self.work, self.processes = bin_dir, work, []
        self.endpoint = f"ipc://{work}/coordinator.sock"
        self.env = dict(os.environ, XDG_CONFIG_HOME=os.path.join(work, "config"))

    def start(self, name, args):
        log = open(os.path.join(self.work, name + ".log"), "w")
        process = subprocess.Popen(args, stdout=log, stderr=subprocess.STDOUT, env=self.env, cwd=self.work)
        self.processes.append((name, process))
        return process

    def portico(self, *args):
        return subprocess.run([os.path.join(self.bin, "portico"), *args], env=self.env, check=True,
                              capture_output=True, text=True).stdout

    def stop(self, show_logs):
        for name, process in reversed(self.processes):
            if process.poll() is None:
                process.send_signal(signal.SIGTERM)
        for name, process in self.processes:
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                process.kill()
            if show_logs:
                with open(os.path.join(self.work, name + ".log")) as log:
                    print(f"--- {name}.log (last lines)\n" + "".join(log.readlines()[-15:]), file=sys.stderr)


def http_status(url, headers=None, method="GET"):
    request = urllib.request.Request(url, headers=headers or {}, method=method)
    try:
        with urllib.request.urlopen(request, timeout=10) as reply:
            return reply.status
    except urllib.error.HTTPError as e:
        return e.code


def wait_for(what, condition, timeout):
    deadline = time.time() + timeout
    while time.time() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.2)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("bin_dir")
    parser.add_argument("--screenshot", help="also save a screenshot of the page (docs/images/dashboard.png)")
    args = parser.parse_args()
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
        from selenium.webdriver.common.by import By
        from selenium.common.exceptions import NoSuchElementException, StaleElementReferenceException
    except ImportError:
        # Debian's python3-selenium is in the system Python's path, which
        # another python3 first on PATH (pyenv, a venv) does not see.
        if os.path.realpath(sys.executable) != os.path.realpath("/usr/bin/python3") and os.path.exists("/usr/bin/python3"):
            os.execv("/usr/bin/python3", ["/usr/bin/python3", *sys.argv])
        print("SKIP: python3-selenium is not installed (deploy/install-deps.sh installs it)")
        return SKIP
    browser, driver_path = find_browser(), shutil.which("chromedriver")
    if not browser or not driver_path:
        print("SKIP: Chromium or chromedriver is not installed (deploy/install-deps.sh installs them)")
        return SKIP

    started = time.time()
    work = tempfile.mkdtemp(prefix="portico-dashboard-test-")
    farm = Farm(os.path.abspath(args.bin_dir), work)
    failed = True
    driver = None
    try:
        farm.portico("scene", "generate", "--preset", "demo", os.path.join(work, "store"))
        farm.start("coordinator", [os.path.join(farm.bin, "portico-coordinator"), "--listen", farm.endpoint,
                                   "--db", os.path.join(work, "jobs.db")])
        wait_for("the coordinator's socket", lambda: os.path.exists(f"{work}/coordinator.sock"), 20)
        for name in ("w1", "w2"):
            farm.start(name, [os.path.join(farm.bin, "portico-worker"), "--connect", farm.endpoint, "--memory",
                              "1GiB", "--name", name])
        dashboard = farm.start("dashboard", [os.path.join(farm.bin, "portico"), "dashboard", "--coordinator",
                                             farm.endpoint, "--listen", "127.0.0.1:0"])
        printed = wait_for("the dashboard's URL", lambda: re.search(
            r"http://127\.0\.0\.1:(\d+)/\?token=([0-9a-f]{64})", open(f"{work}/dashboard.log").read()), 20)
        base, token = f"http://127.0.0.1:{printed.group(1)}", printed.group(2)
        token_file = os.path.join(work, "config", "portico", "dashboard", "token")
        assert open(token_file).read().strip() == token, "the printed token is the one kept"
        assert os.stat(token_file).st_mode & 0o777 == 0o600, oct(os.stat(token_file).st_mode)
        assert os.stat(os.path.dirname(token_file)).st_mode & 0o777 == 0o700

        # Two jobs: A renders in passes for 20 s from the corridor, its rays spread through
        # the doors (its preview changes with each pass, its cells on the plan), B
        # has a long photon pass and waits behind A, to be cancelled.
        job_a = int(farm.portico("submit", "--coordinator", farm.endpoint, f"{work}/store", "-o", f"{work}/a.png",
                                 "--camera", "corridor", "--photons", "400000", "--spp", "2", "--time-limit", "20",
                                 "--max-passes", "40", "--width", "400", "--height", "260").strip())
        job_b = int(farm.portico("submit", "--coordinator", farm.endpoint, f"{work}/store", "-o", f"{work}/b.png",
                                 "--photons", "20000000").strip())

        # The token guards every request; actions need its header.
        assert http_status(f"{base}/") == 401
        assert http_status(f"{base}/api/state") == 401
        assert http_status(f"{base}/api/jobs/{job_a}/preview.png") == 401
        assert http_status(f"{base}/?token=" + "0" * 64) == 403
        assert http_status(f"{base}/api/state", {"X-Portico-Token": "0" * 64}) == 403
        assert http_status(f"{base}/api/state", {"Cookie": "portico_dashboard_token=" + "1" * 64}) == 403
        assert http_status(f"{base}/api/state", {"X-Portico-Token": token}) == 200
        cookie = {"Cookie": "portico_dashboard_token=" + token}
        assert http_status(f"{base}/api/jobs/{job_b}/cancel", cookie, "POST") == 403, "a cookie alone does not act"
        assert http_status(f"{base}/api/jobs/{job_b}/cancel", {"X-Portico-Token": token, "Origin": "http://evil.test"},
                           "POST") == 403, "another site's page does not act"
        assert http_status(f"{base}/api/state", {"X-Portico-Token": token, "Host": "evil.test:80"}) == 403
        assert http_status(f"{base}/api/jobs/{job_b}/priority?priority=5", cookie, "POST") == 403
        assert http_status(f"{base}/api/jobs/{job_b}/priority?priority=5000", {"X-Portico-Token": token}, "POST") == 400

        options = webdriver.ChromeOptions()
        options.binary_location = browser
        for flag in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--window-size=1500,1000"):
            options.add_argument(flag)
        driver = webdriver.Chrome(service=Service(driver_path), options=options)
        driver.set_page_load_timeout(30)

        # Without the token the browser gets the refusal, not the page.
        driver.get(base + "/")
        assert "needs its token" in driver.find_element(By.TAG_NAME, "body").text

        driver.get(f"{base}/?token={token}")
        assert driver.current_url == base + "/", "the token leaves the address bar for a cookie"
        wait_for("job A's row", lambda: driver.execute_script(
            f"const r = document.querySelector('#jobs tr[data-job=\"{job_a}\"]'); if (r) r.click(); return !!r;"), 20)

        # The page redraws its tables with each event: read them in one script, not through stale elements.
        def fraction():
            value = driver.execute_script(
                f"const b = document.querySelector('#jobs tr[data-job=\"{job_a}\"] .bar'); return b && b.dataset.fraction;")
            return float(value) if value else None

        def state(job):
            return driver.execute_script(
                f"const r = document.querySelector('#jobs tr[data-job=\"{job}\"]'); return r && r.dataset.state;")

        first = wait_for("job A's progress", lambda: fraction() is not None and fraction() > 0 and fraction(), 30)
        later = wait_for("job A's progress to advance", lambda: (fraction() or 0) > first and fraction(), 30)
        print(f"job {job_a}: progress {100 * first:.1f} % -> {100 * later:.1f} % on the page")

        def preview():
            """The preview's version and a digest of its decoded pixels."""
            return driver.execute_script("""
                const img = document.getElementById('preview');
                if (!img.complete || !img.naturalWidth || !img.dataset.version) return null;
                const c = document.createElement('canvas');
                c.width = img.naturalWidth; c.height = img.naturalHeight;
                const g = c.getContext('2d'); g.drawImage(img, 0, 0);
                return [img.dataset.version, Array.from(g.getImageData(0, 0, c.width, c.height).data).join(',')];""")

        shown = wait_for("job A's preview", preview, 40)
        changed = wait_for("job A's preview to change",
                           lambda: (p := preview()) and p[0] != shown[0] and p[1] != shown[1] and p, 40)
        digest = lambda p: hashlib.sha256(p[1].encode()).hexdigest()[:12]
        print(f"job {job_a}: preview {digest(shown)} ({shown[0]} camera samples) -> {digest(changed)} "
              f"({changed[0]} camera samples)")
        wait_for("job A's cells on the plan", lambda: driver.execute_script(
            "return document.querySelectorAll('#plans rect[data-state]').length"), 20)

        if args.screenshot:
            time.sleep(1.5)
            # Scaled by Chromium itself (DevTools' captureScreenshot): the page at 2/3 size keeps the PNG under 200 KB.
            width, height = driver.execute_script("return [window.innerWidth, window.innerHeight]")
            shot = driver.execute_cdp_cmd("Page.captureScreenshot", {
                "format": "png", "clip": {"x": 0, "y": 0, "width": width, "height": height, "scale": 0.66}})
            with open(args.screenshot, "wb") as out:
                out.write(base64.b64decode(shot["data"]))
            print(f"wrote {args.screenshot}")

        # A's priority changed from the page, as `portico priority` would.
        field = driver.find_element(By.ID, "priority")
        field.clear()
        field.send_keys("7")
        driver.find_element(By.ID, "priority-set").click()
        wait_for("job A's priority on the page", lambda: driver.execute_script(
            f"const c = document.querySelector('#jobs tr[data-job=\"{job_a}\"] td.priority'); return c && c.textContent;")
            == "7", 20)
        status = json.loads(farm.portico("status", "--coordinator", farm.endpoint, str(job_a), "--json"))
        assert status["priority"] == 7, status.get("priority")
        print(f"job {job_a}: priority 7 set from the page; portico status says {status['priority']}")

        # Cancel B from the page (its confirmation dialog accepted).
        def click_cancel():
            try:
                driver.find_element(By.CSS_SELECTOR, f'#jobs button.cancel[data-job="{job_b}"]').click()
                return True
            except (NoSuchElementException, StaleElementReferenceException):
                return False   # not drawn yet, or redrawn under the click: again

        wait_for("job B's cancel button", click_cancel, 20)
        driver.switch_to.alert.accept()
        wait_for("job B cancelled on the page", lambda: state(job_b) == "cancelled", 20)
        status = json.loads(farm.portico("status", "--coordinator", farm.endpoint, str(job_b), "--json"))
        assert status["state"] == "cancelled", status["state"]
        print(f"job {job_b}: cancelled from the page; portico status says {status['state']}")
        assert dashboard.poll() is None, "the dashboard still serves"

        # Refused at start, in one line: an address beyond loopback, a token others can read.
        def refused(*extra):
            run = subprocess.run([os.path.join(farm.bin, "portico"), "dashboard", "--coordinator", farm.endpoint,
                                  *extra], env=farm.env, capture_output=True, text=True, timeout=20)
            return run.returncode, run.stderr.strip()

        code, error = refused("--listen", "0.0.0.0:8080")
        assert code == 1 and "loopback only" in error and len(error.splitlines()) == 1, (code, error)
        os.chmod(token_file, 0o644)
        code, error = refused("--listen", "127.0.0.1:0")
        assert code == 1 and "readable by other users" in error, (code, error)
        failed = False
        print(f"dashboard test passed in {time.time() - started:.1f} s")
        return 0
    finally:
        if driver:
            driver.quit()
        farm.stop(show_logs=failed)
        if not failed:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
