"""gathering-compare pairs policies on their common seeds: per-episode scores (compare-episodes.csv) and,
in compare.md, each policy against the first: mean difference ± standard error, seeds higher /
equal / lower, and the Wilcoxon signed-rank p, checked against hand values and a brute-force
sign-flip enumeration (the exact null distribution when no two |differences| tie)."""

from __future__ import annotations

import csv
import itertools

import numpy as np
import pytest

from evolution.compare import PER_EPISODE, compare, compare_main, paired_difference, write_outputs
from evolution.policies import make_policy


def exact_signed_rank_p(diff: list[float]) -> float:
    """Two-sided p of the signed-rank statistic by enumerating all 2^n sign patterns
    (zero differences dropped; distinct |differences| assumed)."""
    d = np.array([x for x in diff if x != 0])
    ranks = np.argsort(np.argsort(np.abs(d))) + 1
    observed = ranks[d > 0].sum()
    total = ranks.sum()
    stat = min(observed, total - observed)
    count = 0
    patterns = list(itertools.product((0, 1), repeat=len(d)))
    for signs in patterns:
        w = ranks[np.array(signs, dtype=bool)].sum()
        count += min(w, total - w) <= stat
    return count / len(patterns)


def test_paired_difference_by_hand():
    # differences 2, 0, -1, 5: mean 1.5, sample sd sqrt(7), se sqrt(7)/2
    d = paired_difference([3, 5, 5, 9], [1, 5, 6, 4])
    assert d["diff"] == pytest.approx(1.5) and d["diff_se"] == pytest.approx(np.sqrt(7) / 2)
    assert (d["higher"], d["equal"], d["lower"]) == (2, 1, 1)
    # zero dropped: |d| ranks 2 -> 2, 1 -> 1, 5 -> 3; W+ = 5, W- = 1; P(min <= 1) = 2/8 on each side
    assert d["wilcoxon_p"] == pytest.approx(0.5)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_wilcoxon_p_matches_a_brute_force_enumeration(seed):
    rng = np.random.default_rng(seed)
    base = rng.uniform(0, 100, 9)
    values = base + rng.permutation(np.arange(1, 10) * rng.choice([-1.0, 1.0], 9))  # |d| = 1..9, distinct
    d = paired_difference(values, base)
    assert d["wilcoxon_p"] == pytest.approx(exact_signed_rank_p(list(values - base)))


def test_the_direction_is_policy_minus_first():
    a, b = [10.0, 20.0, 30.0, 45.0], [12.0, 15.0, 25.0, 40.0]
    ab, ba = paired_difference(a, b), paired_difference(b, a)
    assert ab["diff"] == pytest.approx(3.25) and ba["diff"] == pytest.approx(-3.25)
    assert (ab["higher"], ab["lower"]) == (3, 1) == (ba["lower"], ba["higher"])
    assert ab["wilcoxon_p"] == pytest.approx(ba["wilcoxon_p"])
    assert np.isnan(paired_difference(a, a)["wilcoxon_p"])
    with pytest.raises(ValueError, match="same episodes"):
        paired_difference([1.0, 2.0], [1.0])


def row(name: str, ft: list[float]) -> dict:
    return {"policy": name, "sensors": 3, "episodes": len(ft), "ft_mean": float(np.mean(ft)),
            "ft_std": float(np.std(ft)),
            "ft_se": float(np.std(ft, ddof=1) / np.sqrt(len(ft))) if len(ft) > 1 else None,
            "small": 0.0, "medium": 0.0, "large": 0.0, "finished": 0, "steps_to_finish": None,
            PER_EPISODE: [{"policy": name, "seed": s, "ft": f, "small": 0, "medium": 0, "large": 0,
                           "finished": False, "steps": 10} for s, f in enumerate(ft)]}


def test_compare_md_pairs_every_policy_with_the_first_and_episodes_csv_keeps_each_seed(tmp_path):
    rows = [row("wander", [1, 5, 6, 4]), row("champion", [3, 5, 5, 9]), row("random", [0, 5, 6, 4])]
    md, csv_path, _ = write_outputs(rows, tmp_path / "out", "a title")
    text = md.read_text()
    assert "Paired with wander on the same seeds" in text
    assert f"| champion | +1.50 ± {np.sqrt(7) / 2:.2f} | 2 / 1 / 1 | 0.5 |" in text
    assert "| random | -0.25 ± 0.25 | 0 / 3 / 1 |" in text          # one difference: -1
    with open(csv_path) as f:
        assert PER_EPISODE not in next(csv.reader(f))                  # the summary keeps its columns
    with open(tmp_path / "out" / "compare-episodes.csv") as f:
        episodes = list(csv.DictReader(f))
    assert [(e["policy"], int(e["seed"]), float(e["ft"])) for e in episodes[4:8]] == \
        [("champion", 0, 3.0), ("champion", 1, 5.0), ("champion", 2, 5.0), ("champion", 3, 9.0)]


def test_one_episode_or_one_policy_has_no_paired_table(tmp_path):
    md, _, _ = write_outputs([row("wander", [1.0, 2.0])], tmp_path / "a", "t")
    assert "Paired" not in md.read_text()
    single = [row("wander", [1.0]), row("champion", [2.0])]
    md, _, _ = write_outputs(single, tmp_path / "b", "t")
    assert "Paired" not in md.read_text()


def test_compare_keeps_each_episode_in_seed_order(tmp_path, capsys):
    policies = [make_policy("wander"), make_policy("random")]
    seeds = [4, 2, 7]
    rows = compare(policies, {"environment": 1, "num_robots": 4, "max_cycles": 30}, seeds)
    for r in rows:
        assert [e["seed"] for e in r[PER_EPISODE]] == seeds
        assert np.mean([e["ft"] for e in r[PER_EPISODE]]) == pytest.approx(r["ft_mean"])
    out = tmp_path / "cmp"
    assert compare_main(["--policy", "wander", "--policy", "random", "--environment", "1", "--robots", "4",
                         "--steps", "30", "--episodes", "3", "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir() if p.name != ".lock") == \
        ["compare-episodes.csv", "compare.csv", "compare.md", "compare.png"]
    assert "Paired with wander" in (out / "compare.md").read_text()
    assert "compare-episodes.csv" in capsys.readouterr().out


def test_two_champions_of_one_run_keep_their_file_names():
    from evolution.policies.evolved import champion_name

    assert champion_name("runs/S1/champion.json") == "champion:S1"
    assert champion_name("docs/evidence/original-S1-v4/champion-gen55.json") == "champion:original-S1-v4/champion-gen55"
    assert champion_name("champion-gen10.json") == "champion:champion-gen10"
    assert champion_name("champion.json") == "champion:champion.json"


def fake_compare(policies, env_config, seeds):
    """Stands in for the episodes: policy k scores seed * zone_depth + k, so a deeper zone raises
    each seed's ft by a different amount (seed * the change)."""
    from evolution.compare import row_names

    depth = env_config.get("zone_depth", 8.0)
    return [row(name, [s * depth + k for s in seeds]) | {PER_EPISODE: [
        {"policy": name, "seed": s, "ft": s * depth + k, "small": 0, "medium": 0, "large": 0,
         "finished": False, "steps": 10} for s in seeds]}
        for k, name in enumerate(row_names(policies))]


def test_paired_with_pairs_each_policy_with_itself_in_an_earlier_comparison(tmp_path, monkeypatch):
    """--paired-with FOLDER: each policy here against the same policy there, seed by seed
    (difference = here - there); the two wander policies keep their row names (wander#2)."""
    from evolution import compare as compare_module

    monkeypatch.setattr(compare_module, "compare", fake_compare)
    base = ["--policy", "wander", "--policy", "wander", "--episodes", "4", "--seed", "1"]
    assert compare_main(base + ["--out", str(tmp_path / "before")]) == 0
    assert compare_main(base + ["--world", "zone_depth=6", "--paired-with", str(tmp_path / "before"),
                                "--out", str(tmp_path / "after")]) == 0
    text = (tmp_path / "after" / "compare.md").read_text()
    table = text.split(f"Paired with the same policies in {tmp_path / 'before'}")[1]
    # seeds 1..4 at depth 6 against depth 8: differences -2, -4, -6, -8; mean -5, sd sqrt(20/3), se sd/2;
    # all lower, so the two-sided exact p is 2/16
    se = np.sqrt(20 / 3) / 2
    assert f"| wander | -5.00 ± {se:.2f} | 0 / 0 / 4 | 0.12 |" in table
    assert f"| wander#2 | -5.00 ± {se:.2f} | 0 / 0 / 4 | 0.12 |" in table


@pytest.mark.parametrize("case, says", [
    ("no-file", "no compare-episodes.csv in it"),
    ("other-policy", "no episodes of random in compare-episodes.csv; allowed: the policies compared there (wander)"),
    ("other-seeds", "wander ran seeds 1..4 (4) there; allowed: the same --seed and --episodes"),
    ("same-folder", "the same folder as --out"),
    ("one-episode", "--paired-with needs at least 2 episodes"),
    ("broken", "compare-episodes.csv:3: not a row of policy, seed and a finite ft"),
    ("nan", "compare-episodes.csv:3: not a row of policy, seed and a finite ft"),
    ("binary", "compare-episodes.csv: not UTF-8 text"),
])
def test_paired_with_refuses_what_it_cannot_pair_in_one_line(tmp_path, monkeypatch, capsys, case, says):
    from evolution import compare as compare_module

    monkeypatch.setattr(compare_module, "compare", fake_compare)
    before = tmp_path / "before"
    assert compare_main(["--policy", "wander", "--episodes", "4", "--seed", "1", "--out", str(before)]) == 0
    args = {"no-file": ["--policy", "wander", "--episodes", "4", "--seed", "1", "--paired-with", str(tmp_path)],
            "other-policy": ["--policy", "random", "--episodes", "4", "--seed", "1", "--paired-with", str(before)],
            "other-seeds": ["--policy", "wander", "--episodes", "4", "--seed", "2", "--paired-with", str(before)],
            "same-folder": ["--policy", "wander", "--episodes", "4", "--seed", "1", "--paired-with", str(before)],
            "one-episode": ["--policy", "wander", "--episodes", "1", "--seed", "1", "--paired-with", str(before)],
            "broken": ["--policy", "wander", "--episodes", "4", "--seed", "1", "--paired-with", str(before)]}
    args["nan"] = args["binary"] = args["broken"]
    args = args[case]
    out = before if case == "same-folder" else tmp_path / "after"
    episodes = before / "compare-episodes.csv"
    lines = episodes.read_text().splitlines()
    if case in ("broken", "nan"):
        bad = "wander,x,1.0" if case == "broken" else "wander,2,nan"
        episodes.write_text("\n".join(lines[:2] + [bad] + lines[3:]) + "\n")
    if case == "binary":
        episodes.write_bytes(b"policy,seed,ft\n\xff\xfe,1,2\n")
    capsys.readouterr()
    kept = {p.name: p.read_bytes() for p in before.iterdir()}
    assert compare_main(args + ["--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and says in err[0], err
    assert not (tmp_path / "after").exists() and {p.name: p.read_bytes() for p in before.iterdir()} == kept
