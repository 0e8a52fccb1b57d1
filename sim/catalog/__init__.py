"""Declarative data shipped with the package: arms, hands, embodiments, tasks, sensor profiles,
generalization channels and the paper's settings. Everything here is YAML, loaded safely."""
