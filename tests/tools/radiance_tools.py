"""Radiance as the tests and tools find it: the programs of PyPI's `pyradiance`
(installed into the sources' .venv by deploy/install-deps.sh), else Radiance
on PATH. Its programs need RAYPATH to hold its lib/ (skybright.cal, ...)."""
import glob, os, shutil, subprocess, sys

SOURCE_DIR = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))


def find_radiance(source_dir=SOURCE_DIR):
    """(bin directory, lib directory) of a Radiance installation, or None."""
    for package in sorted(glob.glob(os.path.join(source_dir, ".venv", "lib", "python3*", "site-packages", "pyradiance"))):
        if os.access(os.path.join(package, "bin", "rtrace"), os.X_OK):
            return os.path.join(package, "bin"), os.path.join(package, "lib")
    rtrace = shutil.which("rtrace")
    if rtrace:
        return os.path.dirname(rtrace), os.environ.get("RAYPATH", "")
    return None


def radiance_or_skip(source_dir=SOURCE_DIR):
    """find_radiance(), or the test ends here as skipped (exit 77, ctest's SKIP_RETURN_CODE)."""
    radiance = find_radiance(source_dir)
    if radiance is None:
        print("SKIPPED: Radiance is not installed (deploy/install-deps.sh puts pyradiance into .venv)")
        sys.exit(77)
    return radiance


def analyze_or_skip(portico):
    """Ends the test as skipped (exit 77) when this portico has no `analyze` command."""
    commands = subprocess.run([portico, "--help"], capture_output=True, text=True).stdout.splitlines()
    if not any(line.split()[:1] == ["analyze"] for line in commands):
        print("SKIPPED: this portico has no `analyze` command")
        sys.exit(77)


class Checks:
    """A test's checks: each printed ok or FAILED; finish() exits 1 if any failed."""

    def __init__(self):
        self.failures = []

    def __call__(self, condition, what):
        print(("ok: " if condition else "FAILED: ") + what)
        if not condition:
            self.failures.append(what)

    def finish(self):
        print(f"{len(self.failures)} failed" if self.failures else "all passed")
        sys.exit(1 if self.failures else 0)


def environment(radiance):
    """os.environ with the Radiance programs first on PATH and its lib/ on RAYPATH."""
    bin_dir, lib_dir = radiance
    env = dict(os.environ)
    env["PATH"] = bin_dir + os.pathsep + env.get("PATH", "")
    env["RAYPATH"] = os.pathsep.join(p for p in (".", lib_dir, env.get("RAYPATH", "")) if p)
    return env


def version(radiance):
    """'RADIANCE 6.0a ...' as rtrace -version says it."""
    out = subprocess.run(["rtrace", "-version"], env=environment(radiance), capture_output=True, text=True)
    return (out.stdout or out.stderr).strip()


def oconv(radiance, files, octree):
    with open(octree, "wb") as out:
        subprocess.run(["oconv", *files], env=environment(radiance), stdout=out, check=True)


def rtrace_irradiance(radiance, octree, options, sensors):
    """rtrace -h -I OPTIONS OCTREE with `sensors` ((x, y, z, dx, dy, dz) each) on
    its input: the irradiance R, G, B (W/m^2) of each sensor."""
    text = "".join(" ".join(f"{v:.9g}" for v in s) + "\n" for s in sensors)
    out = subprocess.run(["rtrace", "-h", "-I", *options, octree], input=text, env=environment(radiance),
                         capture_output=True, text=True, check=True)
    rows = [tuple(float(v) for v in line.split()) for line in out.stdout.splitlines() if line.strip()]
    if len(rows) != len(sensors):
        raise RuntimeError(f"rtrace gave {len(rows)} values for {len(sensors)} sensors: {out.stderr.strip()}")
    return rows


def lux(rgb):
    """portico's lux: 179 lm/W x Rec. 709 Y (common/analysis/sensor.h)."""
    return 179.0 * (0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2])


def read_pts(path):
    sensors = []
    with open(path) as f:
        for line in f:
            words = line.split("#", 1)[0].split()
            if words:
                sensors.append(tuple(float(w) for w in words[:6]))
    return sensors


def read_results(path):
    """A `portico analyze` results CSV: its rows as dicts, numbers as floats (an empty reading NaN)."""
    import csv
    rows = []
    with open(path) as f:
        for row in csv.DictReader(f):
            for key, value in row.items():
                if key != "room":
                    row[key] = float(value) if value != "" else float("nan")
            rows.append(row)
    return rows


def read_reference(path):
    """A radiance_reference.csv: its rows as dicts of floats (index an int)."""
    rows = []
    with open(path) as f:
        lines = [l for l in f if not l.startswith("#")]
    header = lines[0].strip().split(",")
    for line in lines[1:]:
        values = line.strip().split(",")
        row = {k: float(v) for k, v in zip(header, values)}
        row["index"] = int(row["index"])
        rows.append(row)
    return rows
