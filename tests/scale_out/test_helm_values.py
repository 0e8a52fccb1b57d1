"""deploy/helm/values.yaml, b2d's values for Dagster's Helm chart, checked offline (no cluster, no helm
here): the Kubernetes objects inside them against Kubernetes 1.33's schemas (strict: no unknown field), and
their settings against the plain manifests' (deploy/k8s), so that both routes deploy the same thing. With
Dagster's chart at hand (B2D_DAGSTER_CHART: the folder of `helm pull dagster/dagster --version 1.13.27
--untar`), the values merged onto the chart's defaults are also checked against the chart's own
values.schema.json, and with `helm` installed, every manifest the chart renders against Kubernetes'."""

from __future__ import annotations

import copy
import functools
import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest
import yaml

from loopback_services import REPO

kubernetes_validate = pytest.importorskip("kubernetes_validate",
                                          reason="kubernetes-validate is not installed (pip install -e '.[scale]')")
jsonschema = pytest.importorskip("jsonschema", reason="jsonschema is not installed (pip install -e '.[scale]')")
from referencing import Registry, Resource  # noqa: E402  (comes with jsonschema)
from referencing.exceptions import NoSuchResource  # noqa: E402
from referencing.jsonschema import DRAFT202012  # noqa: E402

HELM, K8S = REPO / "deploy" / "helm", REPO / "deploy" / "k8s"
KUBERNETES_VERSION = "1.33.0"
CHART_VERSION = "1.13.27"           # Dagster's chart follows dagster's version (integrations: 0.29.27)
K8S_DEFINITIONS = (Path(kubernetes_validate.__file__).parent / "kubernetes-json-schema"
                   / f"v{KUBERNETES_VERSION}-local-strict" / "_definitions.json")
NO_CHART = (f"Dagster's chart is not here (helm is not installed, no network): set B2D_DAGSTER_CHART to the folder "
            f"of `helm pull dagster/dagster --version {CHART_VERSION} --untar`")


def _values() -> dict:
    return yaml.safe_load((HELM / "values.yaml").read_text())


def _kubernetes_definitions(uri: str) -> Resource:
    """Kubernetes' definitions as kubernetes-validate ships them (under `$defs`), also under `definitions`,
    where the chart's schema looks for them at kubernetesjsonschema.dev (it names 1.18; the pinned 1.33,
    strict, is the harder test)."""
    if uri != "k8s" and not (uri.startswith("https://kubernetesjsonschema.dev/") and uri.endswith("/_definitions.json")):
        raise NoSuchResource(ref=uri)
    return _kubernetes_resource()


@functools.cache
def _kubernetes_resource() -> Resource:
    definitions = json.loads(K8S_DEFINITIONS.read_text())["$defs"]
    return Resource.from_contents({"$defs": definitions, "definitions": definitions}, default_specification=DRAFT202012)


REGISTRY = Registry(retrieve=_kubernetes_definitions)


def _errors(instance, definition: str) -> list[str]:
    validator = jsonschema.Draft202012Validator({"$ref": f"k8s#/$defs/io.k8s.api.core.v1.{definition}"},
                                                registry=REGISTRY)
    return [f"{'/'.join(map(str, e.absolute_path))}: {e.message}" for e in validator.iter_errors(instance)]


def _embedded_objects(values: dict) -> list[tuple[str, object, str]]:
    """(where, value, Kubernetes definition) of every Kubernetes object inside the values."""
    launcher = values["runLauncher"]["config"]["k8sRunLauncher"]
    found = [("runLauncher volumes", v, "Volume") for v in launcher["volumes"]]
    found += [("runLauncher volumeMounts", m, "VolumeMount") for m in launcher["volumeMounts"]]
    found += [("runLauncher resources", launcher["resources"], "ResourceRequirements"),
              ("runLauncher securityContext", launcher["securityContext"], "SecurityContext")]
    found += [("runLauncher envVars", {"name": n, "value": v}, "EnvVar")
              for n, _, v in (e.partition("=") for e in launcher["envVars"])]
    for d in values["dagster-user-deployments"]["deployments"]:
        found += [(f"deployment {d['name']} podSecurityContext", d["podSecurityContext"], "PodSecurityContext"),
                  (f"deployment {d['name']} resources", d["resources"], "ResourceRequirements")]
        found += [(f"deployment {d['name']} env", {"name": n, "value": v}, "EnvVar") for n, v in d["env"].items()]
    return found


def test_kubernetes_objects_in_the_values_match_the_kubernetes_schema():
    found = _embedded_objects(_values())
    assert len(found) >= 10
    for where, value, definition in found:
        assert not _errors(value, definition), (where, _errors(value, definition))


def test_the_kubernetes_check_rejects_a_broken_object():
    launcher = _values()["runLauncher"]["config"]["k8sRunLauncher"]
    volume = copy.deepcopy(launcher["volumes"][0])
    volume["persistentVolumeClaim"]["claimNmae"] = volume["persistentVolumeClaim"].pop("claimName")
    assert any("claimNmae" in e for e in _errors(volume, "Volume"))
    resources = {"requests": {"cpu": ["1"]}}
    assert _errors(resources, "ResourceRequirements")


def _plain_instance() -> dict:
    maps = {d["metadata"]["name"]: d for p in sorted((K8S / "manifests").glob("*.yaml"))
            for d in yaml.safe_load_all(p.read_text()) if d and d["kind"] == "ConfigMap"}
    return yaml.safe_load(maps["dagster-instance"]["data"]["dagster.yaml"])


def _plain_names(kind: str) -> set[str]:
    return {d["metadata"]["name"] for p in sorted((K8S / "manifests").glob("*.yaml"))
            for d in yaml.safe_load_all(p.read_text()) if d and d["kind"] == kind}


def test_helm_values_deploy_what_the_plain_manifests_deploy():
    values, plain = _values(), _plain_instance()
    plain_launcher = plain["run_launcher"]["config"]
    launcher = values["runLauncher"]["config"]["k8sRunLauncher"]
    assert values["runLauncher"]["type"] == "K8sRunLauncher"
    assert launcher["envVars"] == plain_launcher["env_vars"] and "B2D_EXECUTOR=k8s" in launcher["envVars"]
    assert (launcher["volumes"], launcher["volumeMounts"]) == (plain_launcher["volumes"], plain_launcher["volume_mounts"])
    assert {v["persistentVolumeClaim"]["claimName"] for v in launcher["volumes"]} <= _plain_names("PersistentVolumeClaim")
    assert launcher["resources"] == plain_launcher["resources"]
    # Postgres: the same server, database, user and password secret (key postgresql-password)
    db, pg = plain["storage"]["postgres"]["postgres_db"], values["postgresql"]
    assert (pg["postgresqlHost"], pg["service"]["port"], pg["postgresqlUsername"], pg["postgresqlDatabase"]) == (
        db["hostname"], db["port"], db["username"], db["db_name"])
    assert pg["postgresqlHost"] in _plain_names("Service") and not pg["enabled"]
    assert values["global"]["postgresqlSecretName"] == plain_launcher["postgres_password_secret"]
    assert values["generatePostgresqlPasswordSecret"] is False
    queue = values["dagsterDaemon"]["runCoordinator"]
    assert queue["config"]["queuedRunCoordinator"]["maxConcurrentRuns"] == plain["run_queue"]["max_concurrent_runs"]
    # the code location: the image's own server command, its user, the same settings as runs and steps
    (deployment,) = values["dagster-user-deployments"]["deployments"]
    dockerfile = (K8S / "Dockerfile").read_text()
    cmd = json.loads(re.search(r"^CMD (\[.*?\])", dockerfile, re.S | re.M).group(1).replace("\\\n", ""))
    assert " ".join(deployment["dagsterApiGrpcArgs"]) in " ".join(cmd)
    assert str(deployment["port"]) == cmd[cmd.index("--port") + 1]
    uid = re.search(r"useradd --uid (\d+)", dockerfile).group(1)
    assert deployment["podSecurityContext"]["runAsUser"] == launcher["securityContext"]["runAsUser"] == int(uid)
    assert [f"{k}={v}" for k, v in deployment["env"].items()] == launcher["envVars"]


def _helm_merge(defaults, overrides):
    """Helm's merge of a values file onto a chart's defaults: maps merge key by key, anything else replaces."""
    if isinstance(defaults, dict) and isinstance(overrides, dict):
        merged = dict(defaults)
        for key, value in overrides.items():
            merged[key] = _helm_merge(defaults.get(key), value) if key in defaults else value
        return merged
    return overrides


def _chart() -> Path:
    folder = os.environ.get("B2D_DAGSTER_CHART")
    if not folder:
        pytest.skip(NO_CHART)
    chart = Path(folder)
    assert yaml.safe_load((chart / "Chart.yaml").read_text())["version"] == CHART_VERSION, chart
    return chart


def _chart_errors(chart: Path, values: dict) -> list[str]:
    schema = json.loads((chart / "values.schema.json").read_text())
    merged = _helm_merge(yaml.safe_load((chart / "values.yaml").read_text()), values)
    validator = jsonschema.Draft7Validator(schema, registry=REGISTRY)
    return [f"{'/'.join(map(str, e.absolute_path))}: {e.message}" for e in validator.iter_errors(merged)]


def test_values_match_the_charts_schema():
    chart = _chart()
    assert not _chart_errors(chart, _values())
    broken = _values()
    broken["runLauncher"]["config"]["k8sRunLauncher"]["volumeMount"] = []        # a typo the chart refuses
    assert _chart_errors(chart, broken)


def test_the_chart_renders_manifests_that_match_the_kubernetes_schema(tmp_path):
    chart = _chart()
    if shutil.which("helm") is None:
        pytest.skip("helm is not installed (no Debian package; https://helm.sh/docs/intro/install/)")
    rendered = subprocess.run(["helm", "template", "b2d", str(chart), "-n", "b2d", "-f", str(HELM / "values.yaml")],
                              capture_output=True, text=True, check=True).stdout
    documents = [d for d in yaml.safe_load_all(rendered) if d]
    assert {"Deployment", "ConfigMap", "Service"} <= {d["kind"] for d in documents}
    for document in documents:
        kubernetes_validate.validate(document, KUBERNETES_VERSION, strict=True)
