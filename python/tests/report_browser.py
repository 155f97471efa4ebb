"""An experiment report page (RUN/index.html) opened in headless chromium, with the flags the
dataset report's test uses (tests/it/dataset_fake/mod.rs: load_in_browser).

:func:`browser_checks` loads a copy of the page, beside it so its relative image paths
resolve, with a small script appended that on the load event writes what the page shows
into the DOM; ``--dump-dom`` returns that DOM. The copy loads every image eagerly (the page
lazy-loads them, and an image below the fold would never load headless)."""

import html
import json
import pathlib
import re
import subprocess
import tempfile

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run"]

CHECK = """<script>
window.addEventListener("load", () => {
  const imgs = [...document.images];
  const text = document.body.innerText;
  const out = {
    tables: [...document.querySelectorAll("table")].map(t => t.className),
    table_cells: document.querySelectorAll("table td").length,
    images: imgs.length,
    broken: imgs.filter(i => !(i.complete && i.naturalWidth > 0)).map(i => i.getAttribute("src")),
    svgs: document.querySelectorAll("svg").length,
    pre: document.querySelectorAll("pre").length,
    best: [...document.querySelectorAll("td.best")].map(td => td.innerText.split("\\n")[0]),
    headers: [...document.querySelectorAll("table.grid thead th")].map(th => th.innerText),
    toc: [...document.querySelectorAll("nav.toc a")].map(a => a.getAttribute("href")),
    unresolved: [...document.querySelectorAll('a[href^="#"]')].map(a => a.getAttribute("href"))
      .filter(h => !document.getElementById(decodeURIComponent(h.slice(1)))),
    text: text,
  };
  const pre = document.createElement("pre");
  pre.id = "d2n-check";
  pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
});
</script>"""


def _run(chromium, args, page):
    with tempfile.TemporaryDirectory() as profile:
        return subprocess.run([chromium, *FLAGS, f"--user-data-dir={profile}/profile", *args,
                               pathlib.Path(page).resolve().as_uri()],
                              capture_output=True, text=True, timeout=300)


def browser_checks(chromium, page):
    """What headless chromium shows of ``page``: {"tables": [class per <table>],
    "images", "broken" (src of each <img> that did not load), "toc" (the href of each link
    of the table of contents), "unresolved" (each in-page link whose id is not on the page),
    "text" (the rendered text), ...}; the page itself is left as it is."""
    page = pathlib.Path(page)
    src = page.read_text()
    copy = page.with_name(".browser-check.html")
    copy.write_text(src.replace(' loading="lazy"', "").replace("</body>", CHECK + "</body>"))
    try:
        r = _run(chromium, ["--dump-dom", "--virtual-time-budget=20000"], copy)
    finally:
        copy.unlink()
    m = re.search(r'<pre id="d2n-check">(.*?)</pre>', r.stdout, re.S)
    assert m, f"chromium wrote no check results (exit {r.returncode}): {r.stderr[-2000:]}"
    return json.loads(html.unescape(m.group(1)))


def screenshot(chromium, page, png, size="1400,1800"):
    """A PNG screenshot of ``page`` at window ``size`` written to ``png``."""
    r = _run(chromium, [f"--screenshot={png}", f"--window-size={size}",
                        "--hide-scrollbars"], page)
    assert pathlib.Path(png).is_file(), f"no screenshot (exit {r.returncode}): {r.stderr}"


def markdown_visible(text):
    """The markdown syntax visible in rendered ``text``: table rules, bold markers, headings."""
    found = []
    if "|---" in text or "---|" in text:
        found.append("|---|")
    if "**" in text:
        found.append("**")
    found += [line for line in text.splitlines() if re.match(r"\s*#{1,6} ", line)]
    return found
