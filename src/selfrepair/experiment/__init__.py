"""Experiments: configuration (:mod:`.config`, :mod:`.schema`); missions (:mod:`.missions`, one
cross product over the factor axes of :mod:`.axes`, with stable keys and seeds from :mod:`.keys`,
fault sets from :mod:`.faultsets`, mazes and routes from :mod:`.mazes`, strategy variants from
:mod:`.variants`); the crash-safe results store (:mod:`.store`); parallel runs (:mod:`.runner`,
its pools in :mod:`.backends`, the cold/warm timing policy in :mod:`.timing`); team experiments
(:mod:`.teams`); summaries and the original study's findings (:mod:`.summary`, :mod:`.findings`,
paired tests in :mod:`.stats`); and the report with figures (:mod:`.report`, :mod:`.plots`,
:mod:`.missionplot`, :mod:`.figstyle`, :mod:`.animate`) and the HTML viewer (:mod:`.viewer`).
See docs/experiments.md."""

__all__: list[str] = []  # the names live in the modules; the curated ones are `selfrepair.*`
