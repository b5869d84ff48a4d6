#!/usr/bin/env python3
"""A report in a real browser: Debian's headless Chromium, driven by its chromedriver
through Selenium (python3-selenium).

Makes a report with the CLI (a small scripted study's, or the profile library's evaluation of
the SVC2004 writers: `--library FOLDER`), opens report.html and checks that:
  - the page loads with no console error or warning from the browser;
  - every figure file has its figure on the page, and no figure is missing a file;
  - inside each figure's plot area (its clip rectangle), the figure inline in the page has the
    same pixels as its standalone SVG file opened alone. A figure clipped by another figure's
    rectangle, or cut by the page, differs there.

With `--plan`, a study plan's page instead (`hattr sim plan --html`, the calibration design):
it loads with no console problem, each search has its power-curve figure, the figure's points
are the table's designs, each drawn inside the plot area, and the figure is drawn at its size.

Usage: report_in_chromium.py HATTR_CLI [--library SVC2004_FOLDER | --plan] [--keep DIR]
       (DIR keeps the report and the screenshots)
Exit code: 0 passed, 1 failed (with what differed), 2 bad arguments, 77 skipped (no SVC2004 folder).
"""
import argparse
import base64
import io
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

CHROMIUM = Path("/usr/bin/chromium")
CHROMEDRIVER = Path("/usr/bin/chromedriver")
INSTALL_HINT = ("install Debian's chromium, chromium-driver, python3-selenium and python3-pil "
                "(scripts/install-deps does)")
# Pixels whose colour differs by more than this in a channel count as different; a few may
# differ by anti-aliasing when a figure sits at a fractional position on the page.
CHANNEL_TOLERANCE = 48
MAX_DIFFERENT_FRACTION = 0.002


def fail(message: str) -> None:
    print(f"report_in_chromium: FAILED: {message}")
    sys.exit(1)


def run(cli: str, folder: Path, *args: str) -> None:
    done = subprocess.run([cli, *args], cwd=folder, capture_output=True, text=True)
    if done.returncode != 0:
        fail(f"hattr {' '.join(args)} exited {done.returncode}:\n{done.stdout}\n{done.stderr}")


def make_report(cli: str, folder: Path) -> Path:
    """A study of 3 scripted subjects, 1 training and 3 recall trials per mode, and its report."""
    lines = ["# skill: loop", "t_s,x_mm,y_mm,z_mm,fx_N,fy_N,fz_N,pen_down_bool"]
    lines += [f"{i * 0.01:.2f},{i * 0.2:.1f},{3.0 * (i % 10) / 10:.1f},0,0,0,-1.2,1" for i in range(51)]
    (folder / "expert.csv").write_text("\n".join(lines) + "\n")
    (folder / "study.json").write_text(
        '{"name": "browser", "skill": "loop", "experts": {"loop": "expert.csv"},'
        ' "protocol": {"training_trials": 1, "recall_trials": 3, "rest_s": 0},'
        ' "world": {"relief": {"kind": "flat"}},'
        ' "subjects": {"count": 3, "participant": "script", "options": {"jitter_mm": 2.0}}}\n')
    run(cli, folder, "study", "init", "study.json", "--db", "study.sqlite")
    run(cli, folder, "study", "run", "--db", "study.sqlite")
    run(cli, folder, "study", "report", "--db", "study.sqlite", "--out", "report")
    return folder / "report"


def make_library_report(cli: str, folder: Path, svc2004: Path) -> Path:
    """The SVC2004 writers imported into a library and its evaluation report (one run a writer,
    two feature sets: every figure kind, in seconds)."""
    run(cli, folder, "library", "-L", "lib.sqlite", "import", "svc2004", str(svc2004))
    run(cli, folder, "library", "-L", "lib.sqlite", "evaluate", "--protocol", "svc2004", "--runs", "1",
        "--sets", "shape,force", "-o", "report")
    return folder / "report"


def require_browser() -> None:
    """Fails now, before the study is made, when the browser or its driver is missing."""
    try:
        import selenium  # noqa: F401
    except ImportError:
        fail(f"python3-selenium is missing: {INSTALL_HINT}")
    for program in (CHROMIUM, CHROMEDRIVER):
        if not program.exists():
            fail(f"{program} is missing: {INSTALL_HINT}")


def open_browser():
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    options = webdriver.ChromeOptions()
    options.binary_location = str(CHROMIUM)
    # Root runs this in CI: Chromium's sandbox needs a user namespace it cannot have there.
    for argument in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1400,1000",
                     "--force-device-scale-factor=1", "--hide-scrollbars", "--disable-dev-shm-usage"):
        options.add_argument(argument)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    return webdriver.Chrome(service=Service(str(CHROMEDRIVER)), options=options)


def console_problems(driver) -> list:
    """The browser's console messages at warning level or above (SEVERE, WARNING)."""
    return [entry for entry in driver.get_log("browser") if entry.get("level") in ("SEVERE", "WARNING")]


def shoot(driver, element):
    """The element as the page renders it, wherever it lies on the page (Chromium's own
    screenshot of the element's rectangle, beyond the window if need be)."""
    from PIL import Image
    x, y, width, height = driver.execute_script(
        "const r = arguments[0].getBoundingClientRect();"
        "return [Math.round(r.left + window.scrollX), Math.round(r.top + window.scrollY),"
        " Math.round(r.width), Math.round(r.height)];", element)
    shot = driver.execute_cdp_cmd("Page.captureScreenshot", {
        "format": "png", "captureBeyondViewport": True,
        "clip": {"x": x, "y": y, "width": width, "height": height, "scale": 1}})
    return Image.open(io.BytesIO(base64.b64decode(shot["data"])))


def plot_area(svg_text: str, name: str):
    """The figure's plot area: its clip rectangle, shrunk to whole pixels."""
    match = re.search(r'<clipPath id="[^"]+"><rect x="([-\d.]+)" y="([-\d.]+)" width="([\d.]+)" height="([\d.]+)"',
                      svg_text)
    if match is None:
        fail(f"figures/{name}.svg has no clip rectangle to compare inside")
    x, y, w, h = (float(v) for v in match.groups())
    return (int(x) + 1, int(y) + 1, int(x + w) - 1, int(y + h) - 1)


def different_fraction(a, b) -> float:
    from PIL import ImageChops
    difference = ImageChops.difference(a.convert("RGB"), b.convert("RGB"))
    pixels = difference.getdata()
    different = sum(1 for p in pixels if max(p) > CHANNEL_TOLERANCE)
    return different / max(1, len(pixels))


def check_plan_page(cli: str, keep) -> int:
    """A plan's page: a curve per search, its points the table's designs, inside the plot area."""
    with tempfile.TemporaryDirectory(prefix="hattr-browser-") as scratch:
        folder = Path(scratch)
        run(cli, folder, "sim", "plan", "--calibration", "paired", "--effect-size", "0.8", "--batch", "200",
            "--max-replicates", "4000", "--quiet", "--html", "plan.html")
        driver = open_browser()
        try:
            driver.get((folder / "plan.html").as_uri())
            problems = console_problems(driver)
            if problems:
                fail("the plan page's console:\n" + "\n".join(str(p) for p in problems))
            figures = driver.find_elements("css selector", "figure > svg")
            rows = [r for r in driver.find_elements("css selector", "table tr")
                    if r.find_elements("css selector", "td")]
            if len(figures) != 1:
                fail(f"expected one power-curve figure (one search), found {len(figures)}")
            svg = figures[0]
            points = svg.find_elements("css selector", "circle")
            if not rows or len(points) != len(rows):
                fail(f"the figure has {len(points)} points for the table's {len(rows)} designs")
            # The points are the table's designs: x proportional to its subjects, y to its power.
            subjects = [float(r.find_elements("css selector", "td")[0].text) for r in rows]
            power = [float(r.find_elements("css selector", "td")[1].text.rstrip(" %")) for r in rows]
            cx = sorted(float(c.get_attribute("cx")) for c in points)
            cy = [float(c.get_attribute("cy")) for c in sorted(points, key=lambda c: float(c.get_attribute("cx")))]
            x_scale = (cx[-1] - cx[0]) / (subjects[-1] - subjects[0])
            y_scale = (cy[-1] - cy[0]) / (power[-1] - power[0]) if power[-1] != power[0] else 0.0
            for k in range(len(rows)):
                x_off = abs(cx[0] + (subjects[k] - subjects[0]) * x_scale - cx[k])
                # Power is printed rounded to 1 % (at both ends of the scale too): allow one percent.
                y_off = abs(cy[0] + (power[k] - power[0]) * y_scale - cy[k])
                if x_off > 0.6 or y_off > 1.2 * abs(y_scale) + 0.6:
                    fail(f"point {k} at ({cx[k]}, {cy[k]}) is not the table's {subjects[k]:g} subjects at "
                         f"{power[k]:g} %")
            box = driver.execute_script("const r = arguments[0].getBoundingClientRect(); return [r.left, r.top, "
                                        "r.width, r.height];", svg)
            width, height = float(svg.get_attribute("width")), float(svg.get_attribute("height"))
            if abs(box[2] - width) > 0.5 or abs(box[3] - height) > 0.5:
                fail(f"the figure is drawn at {box[2]} x {box[3]}, expected {width} x {height}")
            # The clip rectangle in the page (a clipPath is not rendered: from its attributes, the
            # figure drawn at its size, viewBox from 0).
            clip = driver.execute_script(
                "const c = arguments[0].querySelector('clipPath rect'); if (!c) return null;"
                "const s = arguments[0].getBoundingClientRect(); const v = n => parseFloat(c.getAttribute(n));"
                "return [s.left + v('x'), s.top + v('y'), s.left + v('x') + v('width'), s.top + v('y') + v('height')];",
                svg)
            if clip is None:
                fail("the figure has no plot area (clip rectangle)")
            outside = []
            for point in points:
                x, y = driver.execute_script("const r = arguments[0].getBoundingClientRect();"
                                             "return [r.left + r.width / 2, r.top + r.height / 2];", point)
                if not (clip[0] - 0.5 <= x <= clip[2] + 0.5 and clip[1] - 0.5 <= y <= clip[3] + 0.5):
                    outside.append((round(x, 1), round(y, 1)))
            if outside:
                fail(f"points drawn outside the plot area {clip}: {outside}")
            if keep:
                keep.mkdir(parents=True, exist_ok=True)
                (keep / "plan.png").write_bytes(driver.get_screenshot_as_png())
                shutil.copy(folder / "plan.html", keep / "plan.html")
        finally:
            driver.quit()
    print(f"report_in_chromium: the plan page, {len(rows)} designs on its curve inside the plot area; "
          "no console problem")
    return 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cli")
    parser.add_argument("--library", type=Path, metavar="SVC2004_FOLDER")
    parser.add_argument("--plan", action="store_true")
    parser.add_argument("--keep", type=Path)
    arguments = parser.parse_args()
    if arguments.plan:
        require_browser()
        return check_plan_page(str(Path(arguments.cli).resolve()), arguments.keep)
    if arguments.library is not None and not arguments.library.is_dir():
        print(f"report_in_chromium: SKIPPED: SVC2004 data not found at {arguments.library}")
        return 77
    try:
        from PIL import Image
    except ImportError:
        fail(f"python3-pil is missing: {INSTALL_HINT}")

    require_browser()
    with tempfile.TemporaryDirectory(prefix="hattr-browser-") as scratch:
        folder = Path(scratch)
        cli = str(Path(arguments.cli).resolve())
        if arguments.library is None:
            report = make_report(cli, folder)
        else:
            report = make_library_report(cli, folder, arguments.library.resolve())
        files = sorted(p.stem for p in (report / "figures").glob("*.svg"))
        if not files:
            fail("the report wrote no figures")
        driver = open_browser()
        try:
            # The page: loads without a console problem, with one figure per file.
            driver.get((report / "report.html").as_uri())
            problems = console_problems(driver)
            if problems:
                fail("the report's console:\n" + "\n".join(str(p) for p in problems))
            ids = driver.execute_script("return Array.from(document.querySelectorAll('figure')).map(f => f.id)")
            if sorted(ids) != files:
                fail(f"the page's figures {sorted(ids)} are not the figure files {files}")
            page_png = driver.get_screenshot_as_png()
            inline = {}
            for name in files:
                svg = driver.find_element("css selector", f"figure[id='{name}'] > svg")
                inline[name] = shoot(driver, svg)
            # Each figure alone, as its file.
            alone = {}
            for name in files:
                driver.get((report / "figures" / f"{name}.svg").as_uri())
                problems = console_problems(driver)
                if problems:
                    fail(f"figures/{name}.svg's console:\n" + "\n".join(str(p) for p in problems))
                alone[name] = shoot(driver, driver.find_element("css selector", "svg"))
        finally:
            driver.quit()

        # Inside each plot area the two must agree.
        failures = []
        for name in files:
            svg_text = (report / "figures" / f"{name}.svg").read_text()
            width, height = (int(v) for v in re.search(r'<svg [^>]*width="(\d+)" height="(\d+)"', svg_text).groups())
            if inline[name].size != (width, height) or alone[name].size != (width, height):
                failures.append(f"{name}: sizes inline {inline[name].size}, alone {alone[name].size}, "
                                f"expected {(width, height)}")
                continue
            box = plot_area(svg_text, name)
            fraction = different_fraction(inline[name].crop(box), alone[name].crop(box))
            print(f"{name}: {fraction:.4%} of the plot area's pixels differ")
            if fraction > MAX_DIFFERENT_FRACTION:
                failures.append(f"{name}: {fraction:.2%} of the plot area's pixels differ from the file's "
                                f"(at most {MAX_DIFFERENT_FRACTION:.2%})")

        if arguments.keep:
            shutil.copytree(report, arguments.keep / "report", dirs_exist_ok=True)
            (arguments.keep / "page.png").write_bytes(page_png)
            for name in files:
                inline[name].save(arguments.keep / f"{name}.inline.png")
                alone[name].save(arguments.keep / f"{name}.alone.png")
        if failures:
            fail("figures that differ inside their plot areas:\n  " + "\n  ".join(failures))
    print(f"report_in_chromium: {len(files)} figures, whole in the page and as files; no console problem")
    return 0


if __name__ == "__main__":
    sys.exit(main())
