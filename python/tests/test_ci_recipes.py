"""The CI recipes in ci/ run the commands .ci/run runs (so they cannot rot unnoticed), and
have the shape the README promises: the wheel installed, a 4-way fuzz matrix with JUnit and
bundles as artifacts, a merge job, a cached corpus."""

import os

import yaml

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def load(name):
    with open(os.path.join(ROOT, "ci", name), encoding="utf-8") as f:
        return yaml.safe_load(f)


def ci_run_lines():
    with open(os.path.join(ROOT, ".ci", "run"), encoding="utf-8") as f:
        return {line.strip() for line in f}


def commands(lines):
    """The lines that run gcl, build the wheel or install it."""
    return [l.strip() for l in lines
            if l.strip().startswith(("gcl ", "maturin ")) or "pip install" in l]


def github_lines(doc):
    for job in doc["jobs"].values():
        for step in job.get("steps", []):
            yield from str(step.get("run", "")).splitlines()


def gitlab_lines(doc):
    for key, job in doc.items():
        if isinstance(job, dict):
            for part in ("before_script", "script"):
                yield from job.get(part, [])


def test_the_recipes_run_the_commands_of_ci_run():
    run = ci_run_lines()
    for name, lines in (("github-actions.yml", github_lines(load("github-actions.yml"))),
                        ("gitlab-ci.yml", gitlab_lines(load("gitlab-ci.yml")))):
        cmds = commands(lines)
        assert any(c.startswith("gcl fuzz host ") for c in cmds), name
        assert any(c.startswith("gcl fuzz merge ") for c in cmds), name
        assert any(c.startswith("gcl check-host ") for c in cmds), name
        # gcl is not on PyPI: the wheel is built once from source, and installed from there.
        assert any(c.startswith("maturin build --release --out gcl-wheel ") for c in cmds), name
        assert any(c == "python -m pip install gcl-wheel/*.whl pyserial" for c in cmds), name
        assert not any("gcl-harness" in c for c in cmds), "{} installs gcl from PyPI".format(name)
        missing = [c for c in cmds if c not in run]
        assert not missing, "{} runs what .ci/run does not: {}".format(name, missing)


def test_github_builds_the_wheel_first_and_every_job_installs_that_artifact():
    jobs = load("github-actions.yml")["jobs"]
    assert list(jobs)[0] == "gcl-wheel"
    build = [str(s.get("run", "")) for s in jobs["gcl-wheel"]["steps"]]
    assert any(r.startswith("maturin build ") for r in build), build
    upload = [s for s in jobs["gcl-wheel"]["steps"] if str(s.get("uses", "")).startswith("actions/upload-artifact")]
    assert upload and upload[0]["with"] == {"name": "gcl-wheel", "path": "gcl-wheel"}
    for name, job in jobs.items():
        if name == "gcl-wheel":
            continue
        needs = job["needs"] if isinstance(job["needs"], list) else [job["needs"]]
        assert "gcl-wheel" in needs, name
        steps = job["steps"]
        got = next(i for i, s in enumerate(steps) if s.get("with", {}).get("name") == "gcl-wheel")
        install = next(i for i, s in enumerate(steps) if "pip install" in str(s.get("run", "")))
        assert got < install, name


def test_gitlab_builds_the_wheel_first_and_every_job_installs_that_artifact():
    doc = load("gitlab-ci.yml")
    assert doc["stages"][0] == "build" and doc["gcl-wheel"]["stage"] == "build"
    assert any(l.startswith("maturin build ") for l in doc["gcl-wheel"]["script"])
    assert doc["gcl-wheel"]["artifacts"]["paths"] == ["gcl-wheel/"]
    assert doc["default"]["before_script"] == ["python -m pip install gcl-wheel/*.whl pyserial"]
    for name, job in doc.items():
        if isinstance(job, dict) and "needs" in job:
            assert "gcl-wheel" in job["needs"], "{} needs only {}: no wheel artifact".format(name, job["needs"])


def test_github_runs_a_four_way_matrix_merged_with_junit_bundles_and_a_cached_corpus():
    doc = load("github-actions.yml")
    jobs = doc["jobs"]
    fuzz = jobs["fuzz-host"]
    assert fuzz["strategy"]["matrix"]["shard"] == [1, 2, 3, 4]
    assert str(doc["env"]["GCL_SHARDS"]) == "4"
    assert fuzz["env"]["GCL_SHARD"] == "${{ matrix.shard }}"
    run = next(s["run"] for s in fuzz["steps"] if "gcl fuzz host" in str(s.get("run")))
    assert "--duration" in run and "--report" in run and "--out" in run and "--shard" in run
    upload = [s for s in fuzz["steps"] if str(s.get("uses", "")).startswith("actions/upload-artifact")]
    assert upload and upload[0]["if"] == "always()"
    merge = jobs["fuzz-merge"]
    assert "fuzz-host" in merge["needs"] and merge["if"] == "always()"
    cache = [s for s in jobs["fuzz-device"]["steps"] if str(s.get("uses", "")).startswith("actions/cache")]
    assert cache and cache[0]["with"]["path"] == "gcl-out/device/corpus"


def test_gitlab_runs_a_four_way_matrix_merged_with_junit_bundles_and_a_cached_corpus():
    doc = load("gitlab-ci.yml")
    fuzz = doc["gcl-fuzz-host"]
    assert fuzz["parallel"] == 4 and str(doc["variables"]["GCL_SHARDS"]) == "4"
    assert fuzz["artifacts"]["when"] == "always"
    assert fuzz["artifacts"]["reports"]["junit"].endswith("junit.xml")
    merge = doc["gcl-fuzz-merge"]
    assert "gcl-fuzz-host" in merge["needs"] and merge["when"] == "always"
    assert doc["gcl-fuzz-device"]["cache"]["paths"] == ["gcl-out/device/corpus"]
