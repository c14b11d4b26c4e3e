"""ci/self_contained.py: the check that keeps the repository free of references outside it."""
import subprocess
import sys

import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[2]

CHECK = ROOT / "ci" / "self_contained.py"


def run_check(repo):
    return subprocess.run(
        [sys.executable, str(CHECK), str(repo)], capture_output=True, text=True
    )


def make_repo(tmp_path, files):
    for name, text in files.items():
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    subprocess.run(["git", "init", "-q", str(tmp_path)], check=True)
    subprocess.run(["git", "-C", str(tmp_path), "add", "-A"], check=True)
    return tmp_path


def test_this_repository_refers_to_nothing_outside_it():
    result = run_check(ROOT)
    assert result.returncode == 0, result.stdout + result.stderr


def test_every_kind_of_outside_reference_is_found(tmp_path):
    repo = make_repo(
        tmp_path,
        {
            "tests/a.rs": 'let p = root.join("../handover/data/reference");\n',
            "tests/b.py": 'REF = ROOT.parent / "handover" / "data"\n',
            "tests/f.py": 'REF = os.path.join(os.path.dirname(repo_root), "handover")\n',
            "tests/g.rs": 'Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().join("x")\n',
            "tests/h.py": 'REF = HERE / ".." / ".." / ".." / "handover"\n',
            "src/c.rs": 'default_value = concat!(env!("CARGO_MANIFEST_DIR"), "/../elsewhere")\n',
            "src/d.rs": 'include_str!("../../../outside.csv")\n',
            "ci/e.sh": "cp /work/main/x y\n",
        },
    )
    result = run_check(repo)
    assert result.returncode == 1
    for where in ["tests/a.rs:1", "tests/b.py:1", "src/c.rs:1", "src/d.rs:1", "ci/e.sh:1",
                  "tests/f.py:1", "tests/g.rs:1", "tests/h.py:1"]:
        assert where in result.stdout, (where, result.stdout)


def test_paths_that_stay_inside_are_accepted(tmp_path):
    repo = make_repo(
        tmp_path,
        {
            "src/bin/x/bench.rs": 'include_str!("../../../tests/data/ref.csv")\n',
            "tests/data/ref.csv": "t\n0\n",
            "tests/data/README.md": "[model](../../src/model.md)\n",
            "src/model.md": "# model\n",
            "ci/run.sh": "python ci/demo.py --out /tmp/x.png\n",
            "tests/conftest.py": 'DATA = pathlib.Path(__file__).parent / "data"\n',
        },
    )
    result = run_check(repo)
    assert result.returncode == 0, result.stdout + result.stderr


def test_a_fuzz_corpus_keeps_only_inputs_the_check_accepts(tmp_path):
    repo = make_repo(tmp_path, {"README.md": "# r\n"})
    corpus = repo / "tests" / "fuzz" / "corpus" / "params_toml"
    corpus.mkdir(parents=True)
    (corpus / "climbs").write_bytes(b'k = "../../../x"\n')
    (corpus / "plain").write_bytes(b"k = 1\n")
    (corpus / "binary").write_bytes(b"\xff\xfe../../..\x00")
    result = subprocess.run(
        [sys.executable, str(CHECK), "--drop", str(corpus)], capture_output=True, text=True
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "1 file(s)" in result.stdout, result.stdout
    assert sorted(p.name for p in corpus.iterdir()) == ["binary", "plain"]
