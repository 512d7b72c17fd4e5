"""The container and Kubernetes files (deploy/container, deploy/k8s), correct by construction:
no container engine or cluster runs here, so this parses them and checks what would break a
deployment — stages, user, health check, packages that exist in Debian and cover the
server's shared libraries, probes, selectors, GPU requests, and server flags the binary
really accepts — and runs the health-check script against a live server.
"""
import re
import shutil
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

import yaml

import ops_util

ROOT = Path(__file__).resolve().parents[2]
CONTAINER = ROOT / "deploy" / "container"
K8S = ROOT / "deploy" / "k8s"
HEALTH_CHECK = CONTAINER / "grpc_health_check.py"


def instructions(containerfile):
    """(INSTRUCTION, arguments) per logical line: continuations joined, comments dropped."""
    text = re.sub(r"\\\n", " ", Path(containerfile).read_text())
    out = []
    for line in text.splitlines():
        line = line.strip()
        if line and not line.startswith("#"):
            word, _, rest = line.partition(" ")
            out.append((word.upper(), rest.strip()))
    return out


def stages(containerfile):
    """Instructions grouped by FROM: [(from_args, [(instr, args), ...]), ...]."""
    result = []
    for instr, args in instructions(containerfile):
        if instr == "FROM":
            result.append((args, []))
        else:
            result[-1][1].append((instr, args))
    return result


def apt_packages(stage_instructions):
    packages = []
    for instr, args in stage_instructions:
        if instr == "RUN" and "apt-get install" in args:
            for part in args.split("&&"):
                if "apt-get install" in part:
                    packages += [w for w in part.split("apt-get install", 1)[1].split() if not w.startswith("-")]
    return packages


def server_flags():
    done = subprocess.run([ops_util.SERVER, "--help"], capture_output=True, text=True, timeout=30)
    return set(re.findall(r"^\s+(--[a-z0-9-]+)", done.stdout + done.stderr, re.MULTILINE))


def apt_known(packages):
    """The packages among `packages` that apt can install (one apt-cache call)."""
    done = subprocess.run(["apt-cache", "policy", *packages], capture_output=True, text=True)
    known = set()
    for block in re.split(r"^(?=\S)", done.stdout, flags=re.M):
        name = block.split(":", 1)[0].strip()
        candidate = re.search(r"Candidate: (\S+)", block)
        if name and candidate and candidate.group(1) != "(none)":
            known.add(name)
    return known


class ContainerfileTest(unittest.TestCase):
    def check_common(self, name):
        built = stages(CONTAINER / name)
        self.assertEqual(len(built), 2, f"{name}: a build stage and a runtime stage")
        self.assertRegex(built[0][0], r"\bAS build$")
        runtime = dict(built[1][1])
        self.assertIn("USER", runtime)
        self.assertNotIn(runtime["USER"], ("root", "0"))
        self.assertIn("grpc_health_check.py", runtime.get("HEALTHCHECK", ""))
        self.assertEqual(runtime.get("EXPOSE", "").split(), ["50051", "9464"])
        copies = [a for i, a in built[1][1] if i == "COPY"]
        self.assertTrue(any(a.startswith("--from=build") and "localizer-server" in a for a in copies))
        self.assertTrue(any("deploy/container/grpc_health_check.py" in a for a in copies))
        for source in re.findall(r"\bCOPY (?!--from)(\S+)", "\n".join(f"COPY {a}" for a in copies)):
            self.assertTrue((ROOT / source).exists(), f"{name} copies {source}, which the repository lacks")
        return built

    def test_cpu_image(self):
        built = self.check_common("Containerfile.cpu")
        build_packages, runtime_packages = apt_packages(built[0][1]), apt_packages(built[1][1])
        # The build stage has what deploy/install.sh installs to build the server.
        for needed in ("libeigen3-dev", "libfftw3-dev", "libgrpc++-dev", "protobuf-compiler-grpc",
                       "libcivetweb-dev", "libgtest-dev", "nlohmann-json3-dev"):
            self.assertIn(needed, build_packages)
        known = apt_known(build_packages + runtime_packages)
        if "build-essential" not in known:
            self.skipTest("apt has no package lists here (apt-get update): package names not checked")
        for p in build_packages + runtime_packages:
            self.assertIn(p, known, f"Debian has no package {p}")

    @unittest.skipUnless(ops_util.have_binaries() and shutil.which("dpkg"), "needs the server binary and dpkg")
    def test_cpu_runtime_packages_cover_the_servers_libraries(self):
        runtime = apt_packages(stages(CONTAINER / "Containerfile.cpu")[1][1])
        ldd = subprocess.run(["ldd", ops_util.SERVER], capture_output=True, text=True, check=True).stdout
        libraries = re.findall(r"=> (/\S+)", ldd)
        closure = subprocess.run(["apt-cache", "depends", "--recurse", "--important", *runtime],
                                 capture_output=True, text=True).stdout
        provided = set(runtime) | set(re.findall(r"^\s*(?:\|?Depends|PreDepends): <?([a-z0-9.+-]+)", closure, re.M)) \
            | set(re.findall(r"^([a-z0-9.+-]+)$", closure, re.M))
        if len(provided) <= len(runtime):
            self.skipTest("apt has no package lists here: dependency closure not checked")
        # One dpkg -S for every library, by real path and by the path ldd printed (usrmerge).
        paths = sorted({str(Path(lib).resolve()) for lib in libraries} | set(libraries))
        owners = subprocess.run(["dpkg", "-S", *paths], capture_output=True, text=True).stdout
        owned = {}
        for line in owners.splitlines():
            package, _, path = line.partition(": ")
            owned[path] = package.split(":")[0]
        for library in libraries:
            package = owned.get(str(Path(library).resolve())) or owned.get(library)
            if package is None:
                continue  # not from a Debian package (nothing to install)
            self.assertIn(package, provided, f"{library} ({package}) is not in the runtime image")

    def test_cuda_image(self):
        built = self.check_common("Containerfile.cuda")
        runtime = apt_packages(built[1][1])
        for needed in ("cuda-cudart-13-0", "libcufft-13-0", "libcurand-13-0"):
            self.assertIn(needed, runtime)

    @unittest.skipUnless(ops_util.have_binaries(), "no localizer-server binary")
    def test_entrypoints_use_flags_the_server_accepts(self):
        flags = server_flags()
        for name in ("Containerfile.cpu", "Containerfile.cuda"):
            runtime = dict(stages(CONTAINER / name)[1][1])
            used = re.findall(r'"(--[a-z0-9-]+)"', runtime["ENTRYPOINT"] + runtime["CMD"])
            self.assertTrue(used)
            self.assertLessEqual(set(used), flags, name)
            # Listening on every interface only with TLS and tokens.
            if "0.0.0.0" in runtime["ENTRYPOINT"]:
                self.assertLessEqual({"--tls-cert", "--tls-key", "--auth-token-file"}, set(used), name)


class KubernetesTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.docs = [d for f in ("localizer.yaml", "localizer-gpu.yaml")
                    for d in yaml.safe_load_all((K8S / f).read_text()) if d]

    def of_kind(self, kind):
        return [d for d in self.docs if d["kind"] == kind]

    def container(self, deployment):
        return deployment["spec"]["template"]["spec"]["containers"][0]

    def test_deployments_probe_grpc_health_and_bound_resources(self):
        deployments = self.of_kind("Deployment")
        self.assertEqual(len(deployments), 2)
        for d in deployments:
            labels = d["spec"]["template"]["metadata"]["labels"]
            self.assertLessEqual(d["spec"]["selector"]["matchLabels"].items(), labels.items())
            c = self.container(d)
            ports = {p["name"]: p["containerPort"] for p in c["ports"]}
            self.assertEqual(ports, {"grpc": 50051, "metrics": 9464})
            # kubelet's gRPC probe cannot speak TLS: the image's health check does, with the
            # mounted CA and probe certificate (mutual TLS: --tls-client-ca in the args).
            mounts = {m["name"]: m["mountPath"] for m in c["volumeMounts"]}
            self.assertEqual(mounts, {"tls": "/etc/localizer/tls", "auth": "/etc/localizer/auth"})
            secrets = {v["name"]: v["secret"]["secretName"] for v in d["spec"]["template"]["spec"]["volumes"]}
            self.assertEqual(secrets, {"tls": "localizer-tls", "auth": "localizer-auth"})
            self.assertIn("--tls-client-ca", c["args"])
            for probe in ("readinessProbe", "livenessProbe"):
                command = c[probe]["exec"]["command"]
                self.assertIn("/usr/local/bin/grpc_health_check.py", command, f"{d['metadata']['name']} {probe}")
                self.assertEqual(command[-1], "127.0.0.1:50051")
                for flag in ("--tls-ca", "--tls-cert", "--tls-key"):
                    path = command[command.index(flag) + 1]
                    self.assertTrue(path.startswith("/etc/localizer/tls/"), path)
            for kind in ("requests", "limits"):
                self.assertIn("cpu", c["resources"][kind])
                self.assertIn("memory", c["resources"][kind])
            self.assertTrue(d["spec"]["template"]["spec"]["securityContext"]["runAsNonRoot"])

    def test_services_and_budget_select_the_pods(self):
        pod_labels = [d["spec"]["template"]["metadata"]["labels"] for d in self.of_kind("Deployment")]
        services = {s["metadata"]["name"]: s for s in self.of_kind("Service")}
        self.assertEqual(set(services), {"localizer-grpc", "localizer-metrics"})
        grpc_service = services["localizer-grpc"]
        self.assertEqual(grpc_service["spec"]["sessionAffinity"], "ClientIP")
        self.assertEqual(grpc_service["spec"]["ports"][0]["port"], 50051)
        self.assertEqual(services["localizer-metrics"]["spec"]["clusterIP"], "None")
        self.assertEqual(services["localizer-metrics"]["spec"]["ports"][0]["port"], 9464)
        selectors = [s["spec"]["selector"] for s in services.values()]
        selectors.append(self.of_kind("PodDisruptionBudget")[0]["spec"]["selector"]["matchLabels"])
        for selector in selectors:
            for labels in pod_labels:  # every pod, CPU and GPU, is behind every Service
                self.assertLessEqual(selector.items(), labels.items())
        # Prometheus's DNS job names the headless Service.
        prometheus = (ROOT / "deploy" / "prometheus" / "prometheus.yml").read_text()
        self.assertIn("localizer-metrics.localizer.svc.cluster.local", prometheus)

    def test_the_gpu_deployment_asks_for_a_gpu_node(self):
        gpu = next(d for d in self.of_kind("Deployment") if d["metadata"]["name"] == "localizer-gpu")
        c = self.container(gpu)
        self.assertEqual(c["resources"]["limits"]["nvidia.com/gpu"], 1)
        self.assertIn("nvidia.com/gpu.present", gpu["spec"]["template"]["spec"]["nodeSelector"])
        self.assertTrue(any(t["key"] == "nvidia.com/gpu" for t in gpu["spec"]["template"]["spec"]["tolerations"]))
        self.assertEqual(c["image"], "localizer:cuda")

    @unittest.skipUnless(ops_util.have_binaries(), "no localizer-server binary")
    def test_args_are_flags_the_server_accepts(self):
        flags = server_flags()
        for d in self.of_kind("Deployment"):
            used = {a for a in self.container(d)["args"] if a.startswith("--")}
            self.assertLessEqual(used, flags, d["metadata"]["name"])


@unittest.skipUnless(ops_util.have_binaries(), "no localizer-server binary")
class HealthCheckScriptTest(unittest.TestCase):
    def run_check(self, target):
        return subprocess.run([sys.executable, str(HEALTH_CHECK), target], capture_output=True, text=True, timeout=30)

    def test_serving_server_passes_and_a_closed_port_fails(self):
        tmp = tempfile.mkdtemp(prefix="localizer-health-")
        server = ops_util.Server(tmp, "instance")
        try:
            ok = self.run_check(server.grpc_target)
            self.assertEqual(ok.returncode, 0, ok.stdout + ok.stderr)
            self.assertIn("SERVING", ok.stdout)
        finally:
            server.stop()
            shutil.rmtree(tmp, ignore_errors=True)
        down = self.run_check(f"127.0.0.1:{ops_util.free_port()}")
        self.assertEqual(down.returncode, 2, down.stdout + down.stderr)

    @unittest.skipUnless(shutil.which("openssl"), "no openssl CLI (Debian: openssl) for test certificates")
    def test_mutual_tls_server_passes_with_the_probe_certificate_only(self):
        tmp = tempfile.mkdtemp(prefix="localizer-health-tls-")
        pki = Path(tmp) / "pki"
        subprocess.run(["bash", str(ROOT / "deploy" / "tls" / "make_test_certs.sh"), str(pki)], check=True,
                       capture_output=True)
        server = ops_util.Server(tmp, "tls", ["--tls-cert", str(pki / "server.crt"), "--tls-key",
                                              str(pki / "server.key"), "--tls-client-ca", str(pki / "ca.crt"),
                                              "--auth-token-file", str(pki / "tokens")])
        tls = ["--tls-ca", str(pki / "ca.crt"), "--tls-server-name", "localhost"]
        cert = ["--tls-cert", str(pki / "client.crt"), "--tls-key", str(pki / "client.key")]
        try:
            ok = subprocess.run([sys.executable, str(HEALTH_CHECK), *tls, *cert, server.grpc_target],
                                capture_output=True, text=True, timeout=30)
            self.assertEqual(ok.returncode, 0, ok.stdout + ok.stderr)
            no_cert = subprocess.run([sys.executable, str(HEALTH_CHECK), *tls, server.grpc_target],
                                     capture_output=True, text=True, timeout=30)
            self.assertEqual(no_cert.returncode, 2, no_cert.stdout + no_cert.stderr)
            plain = self.run_check(server.grpc_target)
            self.assertEqual(plain.returncode, 2, plain.stdout + plain.stderr)
        finally:
            server.stop()
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    unittest.main()
