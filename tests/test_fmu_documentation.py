"""The documentation inside each FMU (documentation/index.html, written by
src/fmi/package_fmu.py from the model description and src/models/<Name>/README.md)
reads for someone who has the FMU and not the repository:

- no project label ("seed 000"), no issue number, no repository path (src/, ssp/,
  tests/, ...): the papers are numbered references ("ref. 1"), cited in full (authors, title,
  where it appeared) in a references section: every paper the page cites, and
  only those;
- a "Validity and limits" section per model;
- the Markdown rendered: no raw emphasis markers, code fences or table rules left;
- the licences of what the binaries contain: the GCC Runtime Library Exception in
  every FMU, the mingw-w64 runtime's notices in each one with binaries/win64;
- a win64 DLL older than the sources it is built from is not packed (a warning
  says so), so the linux build never ships another build's DLL beside its own.
"""
import json
import os
import re
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import pytest

from artibus import fmu_dir
from conftest import packer_inputs

ROOT = Path(__file__).resolve().parents[1]
NAMES = re.findall(r"^add_fmu\((\w+)", (ROOT / "CMakeLists.txt").read_text(), re.M)
# and the FMI 3.0-only ones: the LS-BUS nodes are add_fmu(<Name> LSBUS ...) above; the bus simulation
NAMES += ["CanBus"]
PAPERS = {k: v for k, v in json.loads((ROOT / "src/models/papers.json").read_text(encoding="utf-8")).items()
          if not k.startswith("_")}
REPO_PATH = re.compile(r"(?<![\w/.])(?:src|ssp|tests|scripts|docs|modelDescription|benchmarks|build[\w-]*|fmus|"
                       r"\.venv)/")


def fmu(name):
    """The FMI 2.0 build, or for an FMU built in FMI 3.0 only (the LS-BUS ones) that one (a node's
    triggered form in fmus/fmi3/lsbus-triggered/)."""
    p = fmu_dir() / f"{name}.fmu"
    if not p.is_file() and (fmu_dir() / "fmi3" / f"{name}.fmu").is_file():
        p = fmu_dir() / "fmi3" / f"{name}.fmu"
    if not p.is_file() and (fmu_dir() / "fmi3" / "lsbus-triggered" / f"{name}.fmu").is_file():
        p = fmu_dir() / "fmi3" / "lsbus-triggered" / f"{name}.fmu"     # an LS-BUS node's triggered form
    if not p.is_file():
        pytest.skip(f"{p} not built (scripts/setup.sh)")
    return p


def page(name):
    with zipfile.ZipFile(fmu(name)) as z:
        return z.read("documentation/index.html").decode("utf-8")


def text_of(html):
    """The page's text without its tags (a link's target is no text the reader sees)."""
    import html as h
    return h.unescape(re.sub(r"<[^>]+>", " ", html))


@pytest.mark.parametrize("name", NAMES)
def test_no_labels_issues_or_repository_paths(name):
    text = text_of(page(name))
    for bad in (r"\bseeds? 0\d\d", r"\bissues? \d", r"\bissue #"):
        m = re.search(bad, text, re.I)
        assert not m, f"{name}: documentation says {text[max(0, m.start() - 60):m.end() + 40]!r}"
    m = REPO_PATH.search(text)
    assert not m, f"{name}: a repository path in its documentation: {text[max(0, m.start() - 60):m.end() + 60]!r}"


@pytest.mark.parametrize("name", NAMES)
def test_papers_cited_in_full(name):
    html = page(name)
    folder = ROOT / "src/models" / name
    if not folder.is_dir() and name.endswith("_Triggered"):      # a node's triggered form: the node's text
        folder = ROOT / "src/models" / name.removesuffix("_Triggered")
    readme = (folder / "README.md").read_text(encoding="utf-8")
    xml = next(p for p in (ROOT / "modelDescription" / f"{name}.xml",          # FMI 2.0 (and 3.0)
                           ROOT / "modelDescription" / "lsbus" / f"{name}.xml",  # an LS-BUS node
                           ROOT / "modelDescription" / "fmi3" / f"{name}.xml")   # FMI 3.0 only
               if p.is_file()).read_text(encoding="utf-8")
    cited = set(re.findall(r"\b[Ss]eeds? (\d{3})\b", readme + xml)) & set(PAPERS)
    listed = re.findall(r'<li id="ref-(\d{3})"', html)
    assert sorted(listed) == sorted(cited), f"{name}: references {listed}, the texts cite {sorted(cited)}"
    for key in cited:
        p = PAPERS[key]
        entry = re.search(rf'<li id="ref-{key}"[^>]*>(.*?)</li>', html, re.S).group(1)
        entry = text_of(entry)
        assert p["title"] or p["subject"], key
        for field in ("authors", "title", "venue", "year", "doi"):
            if p.get(field):
                assert p[field] in entry, f"{name}: reference {key} lacks its {field} {p[field]!r}"
        if not p.get("year"):
            assert "year" in entry.lower(), f"{name}: reference {key} does not say its year is unknown"
    # a reference number in the text for each paper, and none beyond them
    numbers = {int(n) for n in re.findall(r"\bref\. (\d+)\b", text_of(re.sub(r'<h2 id="references">.*?</ol>', "", html, flags=re.S)))}
    assert numbers == set(range(1, len(cited) + 1)), f"{name}: reference numbers {sorted(numbers)}"


@pytest.mark.parametrize("name", NAMES)
def test_validity_section_and_markdown_rendered(name):
    html = page(name)
    m = re.search(r"<h3>Validity and limits</h3>\s*(<ul>.*?</ul>|<p>.*?</p>)", html, re.S)
    assert m, f"{name}: no 'Validity and limits' section"
    assert len(text_of(m.group(1)).split()) >= 12, f"{name}: the validity section says next to nothing"
    body = text_of(html.split("<body>")[1])
    for raw in ("**", "```", "| ---", "|---"):
        assert raw not in body, f"{name}: raw Markdown {raw!r} in its documentation"
    assert not re.search(r"(?<![\w*])\*[A-Za-z][^*\n]*\*(?![\w*])", body), f"{name}: raw *emphasis*"
    assert not re.search(r"^#+ ", body, re.M), f"{name}: a raw Markdown heading"


@pytest.mark.parametrize("name", NAMES)
def test_runtime_licences(name):
    with zipfile.ZipFile(fmu(name)) as z:
        names = z.namelist()
        html = z.read("documentation/index.html").decode("utf-8")
    lic = "documentation/licenses/"
    assert lic + "GCC-runtime-library-exception-3.1.txt" in names
    win64 = f"binaries/win64/{name}.dll" in names or f"binaries/x86_64-windows/{name}.dll" in names
    assert (lic + "mingw-w64-runtime.txt" in names) == win64, f"{name}: the mingw-w64 notice iff win64"
    assert ('href="licenses/mingw-w64-runtime.txt"' in html) == win64
    text = (ROOT / "licenses/GCC-runtime-library-exception-3.1.txt").read_text()
    assert "GCC RUNTIME LIBRARY EXCEPTION" in text and "Version 3.1" in text
    text = (ROOT / "licenses/mingw-w64-runtime.txt").read_text()
    assert "Zope Public License 2.1" in text and "winpthreads" in text


def test_stale_win64_dll_is_not_packed(tmp_path):
    """A DLL older than a source of its model is left out with a warning naming both;
    touched newer, the same DLL is packed."""
    name = "TrainGuidance"
    tree, gen = packer_inputs(fmu(name), tmp_path)
    win = tmp_path / "win64"
    win.mkdir()
    dll = win / f"{name}.dll"
    dll.write_bytes(b"MZ an old build's DLL")
    old = (ROOT / "src/models/TrainGuidance/guidance.c").stat().st_mtime - 3600
    os.utime(dll, (old, old))
    sources = ["src/models/TrainGuidance/model.c", "src/models/TrainGuidance/guidance.c"]
    env = {k: v for k, v in os.environ.items() if k not in ("LD_PRELOAD", "SOURCE_DATE_EPOCH")}

    def pack(out):
        p = subprocess.run([sys.executable, str(ROOT / "src/fmi/package_fmu.py"), "--name", name,
                            "--root", str(ROOT), "--xml", str(ROOT / "modelDescription" / f"{name}.xml"),
                            "--gen", str(gen), "--tree", str(tree), "--fmu", str(out),
                            f"--win64-dir={win}", "--sources", *sources, "--resources"],
                           capture_output=True, text=True, env=env)
        assert p.returncode == 0, p.stderr
        with zipfile.ZipFile(out) as z:
            return p.stderr, z.namelist()

    err, names = pack(tmp_path / "stale.fmu")
    assert f"binaries/win64/{name}.dll" not in names
    assert "binaries/win64 left out" in err and str(dll) in err, err
    # it names the newest of the files the DLL is built from (whichever that is in this checkout)
    newer = re.search(r"is older than (\S+)", err).group(1)
    assert (ROOT / newer).is_file() and (ROOT / newer).stat().st_mtime > old, err
    assert "documentation/licenses/mingw-w64-runtime.txt" not in names
    now = time.time()
    os.utime(dll, (now, now))
    err, names = pack(tmp_path / "fresh.fmu")
    assert f"binaries/win64/{name}.dll" in names and "left out" not in err
    assert "documentation/licenses/mingw-w64-runtime.txt" in names
