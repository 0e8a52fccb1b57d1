"""The Kubernetes deployment in deploy/k8s, checked offline (no cluster is reachable): every manifest
against the pinned Kubernetes schemas (kubernetes-validate, strict: no unknown fields), the instance's
dagster.yaml against Dagster's and dagster-k8s's own config schemas, the references between the objects,
and the Dockerfile against the checkout it copies."""

from __future__ import annotations

import copy
import re
import tomllib

import pytest
import yaml

from loopback_services import REPO

kubernetes_validate = pytest.importorskip("kubernetes_validate",
                                          reason="kubernetes-validate is not installed (pip install -e '.[scale]')")
K8S = REPO / "deploy" / "k8s"
KUBERNETES_VERSION = "1.33.0"       # the schemas the manifests are held to


def _documents() -> list[dict]:
    return [d for path in sorted((K8S / "manifests").glob("*.yaml")) for d in yaml.safe_load_all(path.read_text()) if d]


def _of_kind(kind: str) -> dict[str, dict]:
    return {d["metadata"]["name"]: d for d in _documents() if d["kind"] == kind}


def _instance() -> dict:
    return yaml.safe_load(_of_kind("ConfigMap")["dagster-instance"]["data"]["dagster.yaml"])


def _pod_specs() -> dict[str, dict]:
    return {name: d["spec"]["template"]["spec"] for kind in ("Deployment", "StatefulSet")
            for name, d in _of_kind(kind).items()}


@pytest.mark.parametrize("document", _documents(), ids=lambda d: f"{d['kind']}/{d['metadata']['name']}")
def test_manifest_matches_the_kubernetes_schema(document):
    kubernetes_validate.validate(document, KUBERNETES_VERSION, strict=True)
    assert document["metadata"].get("namespace", "b2d") == "b2d"


def test_the_validator_rejects_a_broken_manifest():
    broken = copy.deepcopy(_of_kind("Deployment")["dagster-daemon"])
    broken["spec"]["replicas"] = "one"
    with pytest.raises(kubernetes_validate.ValidationError):
        kubernetes_validate.validate(broken, KUBERNETES_VERSION, strict=True)
    broken = copy.deepcopy(_of_kind("Deployment")["dagster-daemon"])
    broken["spec"]["template"]["spec"]["containers"][0]["comand"] = ["typo"]
    with pytest.raises(kubernetes_validate.ValidationError):
        kubernetes_validate.validate(broken, KUBERNETES_VERSION, strict=True)


def test_kustomization_applies_every_manifest():
    listed = yaml.safe_load((K8S / "kustomization.yaml").read_text())["resources"]
    assert listed == [f"manifests/{p.name}" for p in sorted((K8S / "manifests").glob("*.yaml"))]


def test_instance_yaml_matches_dagster_and_dagster_k8s_schemas(tmp_path):
    pytest.importorskip("dagster_k8s", reason="dagster-k8s is not installed (pip install -e '.[scale]')")
    from dagster._config import validate_config
    from dagster._core.instance.config import dagster_instance_config
    from dagster_k8s import K8sRunLauncher
    from dagster_postgres import DagsterPostgresStorage

    (tmp_path / "dagster.yaml").write_text(yaml.safe_dump(_instance()))
    config, _ = dagster_instance_config(str(tmp_path))           # raises on a key Dagster does not know
    launcher = config["run_launcher"]
    assert (launcher["module"], launcher["class"]) == ("dagster_k8s", "K8sRunLauncher")
    checked = validate_config(K8sRunLauncher.config_type(), launcher["config"])
    assert checked.success, checked.errors
    checked = validate_config(DagsterPostgresStorage.config_type(), config["storage"]["postgres"])
    assert checked.success, checked.errors


def test_objects_refer_to_each_other_consistently():
    launcher = _instance()["run_launcher"]["config"]
    config_maps, claims = set(_of_kind("ConfigMap")), set(_of_kind("PersistentVolumeClaim"))
    assert launcher["instance_config_map"] in config_maps
    assert launcher["service_account_name"] in _of_kind("ServiceAccount")
    assert {v["persistentVolumeClaim"]["claimName"] for v in launcher["volumes"]} <= claims
    secret_refs, images = set(), set()
    for name, spec in _pod_specs().items():
        for volume in spec.get("volumes", []):
            if "configMap" in volume:
                assert volume["configMap"]["name"] in config_maps, name
            if "persistentVolumeClaim" in volume:
                assert volume["persistentVolumeClaim"]["claimName"] in claims, name
        for container in spec["containers"]:
            images.add(container["image"])
            for env in container.get("env", []):
                ref = env.get("valueFrom", {}).get("secretKeyRef")
                if ref:
                    secret_refs.add((ref["name"], ref["key"]))
    # dagster-k8s injects the key postgresql-password of postgres_password_secret into run and step pods
    assert secret_refs == {(launcher["postgres_password_secret"], "postgresql-password")}
    assert images - {"postgres:15.10-bookworm"} == {"b2d:0.1.0"}
    code_env = {e["name"]: e.get("value") for e in _pod_specs()["b2d-code"]["containers"][0]["env"]}
    assert code_env["DAGSTER_CURRENT_IMAGE"] == "b2d:0.1.0"
    # the workspace points at the code server's service and port
    server = yaml.safe_load(_of_kind("ConfigMap")["dagster-workspace"]["data"]["workspace.yaml"])["load_from"][0]
    service = _of_kind("Service")[server["grpc_server"]["host"]]
    assert server["grpc_server"]["port"] == service["spec"]["ports"][0]["port"]
    assert "B2D_EXECUTOR=k8s" in launcher["env_vars"]


def test_dockerfile_copies_every_package_and_installs_the_scale_extra():
    text = (K8S / "Dockerfile").read_text()
    project = tomllib.loads((REPO / "pyproject.toml").read_text())
    copied = {src for line in re.findall(r"^COPY (.+)$", text, re.M) for src in line.split()[:-1]}
    assert all((REPO / src).exists() for src in copied), copied
    packages = {p.rstrip("*") for p in project["tool"]["setuptools"]["packages"]["find"]["include"]}
    assert packages <= copied, packages - copied
    assert 'pip install --no-cache-dir -e ".[scale]"' in text and "scale" in project["project"]["optional-dependencies"]
    torch = next(d for d in project["project"]["dependencies"] if d.startswith("torch"))
    assert f"pip install --no-cache-dir {torch} " in text                # the same pin as the project
    assert '"--module-name", "b2d_pipeline.definitions", "--attribute", "defs"' in text


def test_k8s_executor_is_dagster_k8s_job_executor():
    dagster_k8s = pytest.importorskip("dagster_k8s", reason="dagster-k8s is not installed (pip install -e '.[scale]')")
    from b2d_pipeline.scale_out import executor_named

    assert executor_named("k8s") is dagster_k8s.k8s_job_executor
