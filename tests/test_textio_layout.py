"""The two layout rules every file reader and report writer shares (selfrepair.textio)."""

from __future__ import annotations

from pathlib import Path

import pytest

from selfrepair.experiment.config import parse_config
from selfrepair.experiment.report import markdown_table as report_table
from selfrepair.textio import markdown_table, source_dir


def test_relative_paths_resolve_against_the_file_or_the_working_directory(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    assert source_dir(str(tmp_path / "x.toml")) == tmp_path
    monkeypatch.chdir(tmp_path / ".")
    assert source_dir("<string>") == Path.cwd()
    assert source_dir("<input>") == tmp_path
    assert source_dir("plain.toml") == Path(".")


def test_experiment_configs_take_their_base_directory_from_source_dir(tmp_path: Path) -> None:
    text = 'name = "x"\n[[mazes]]\nbundled = "narrow-short"\n[[strategies]]\nname = "replan"\n'
    filed = parse_config(text, source=str(tmp_path / "e.toml"))
    assert filed.base_dir == tmp_path
    assert parse_config(text).base_dir == Path.cwd()


def test_markdown_table_aligns_the_first_column_left_and_the_rest_right() -> None:
    text = markdown_table(("strategy", "n", "ms"), [("replan", "3", "1.5"), ("a, b", "10", "-")])
    assert text.splitlines() == [
        "| strategy | n | ms |",
        "|:---|---:|---:|",
        "| replan | 3 | 1.5 |",
        "| a, b | 10 | - |",
    ]
    assert markdown_table(("only",), []) == "| only |\n|:---|"
    assert report_table is markdown_table  # the report's name is the same function
