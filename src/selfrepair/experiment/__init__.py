"""Experiments: configuration (:mod:`.config`), missions with stable keys (:mod:`.missions`), the
crash-safe results store (:mod:`.store`), parallel runs (:mod:`.runner`), summaries and the
original study's findings (:mod:`.findings`), and the report with figures (:mod:`.report`,
:mod:`.plots`, :mod:`.animate`). See docs/experiments.md."""

__all__: list[str] = []  # the names live in the modules; the curated ones are `selfrepair.*`
