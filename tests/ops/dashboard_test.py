"""The Grafana dashboard (deploy/grafana) and the alert rules (deploy/prometheus) read only
metrics a live localizer-server exposes: every metric name in their queries must be in a
/metrics scrape taken after a simulated session ran, so neither can drift from the server.
"""
import json
import re
import shutil
import tempfile
import unittest
from pathlib import Path

import yaml

import ops_util

ROOT = Path(__file__).resolve().parents[2]
DASHBOARD = ROOT / "deploy" / "grafana" / "localizer-fleet.json"
ALERTS = ROOT / "deploy" / "prometheus" / "alerts.yml"
# Series Prometheus makes itself.
PROMETHEUS_SERIES = {"up"}
IDENTIFIER = re.compile(r"\b(localizer_[a-z0-9_]+|up)\b(?!\s*\()")


def dashboard_queries():
    dash = json.loads(DASHBOARD.read_text())
    exprs = [t["expr"] for p in dash["panels"] for t in p.get("targets", [])]
    exprs += [v["query"] for v in dash["templating"]["list"] if v.get("type") == "query"]
    return exprs


def alert_queries():
    rules = yaml.safe_load(ALERTS.read_text())
    return [r["expr"] for g in rules["groups"] for r in g["rules"]]


def names_in(expr):
    # Label values in quotes and label names after by/without are not metric names.
    expr = re.sub(r'"[^"]*"', '""', expr)
    expr = re.sub(r"\b(by|without)\s*\([^)]*\)", "", expr)
    expr = re.sub(r"\{[^}]*\}", "{}", expr)
    return set(IDENTIFIER.findall(expr))


class QueryParsingTest(unittest.TestCase):
    def test_names_are_found_and_labels_are_not(self):
        self.assertEqual(names_in('sum by (localizer_x) (rate(localizer_a_bucket{stage="localizer_b"}[5m]))'),
                         {"localizer_a_bucket"})
        self.assertEqual(names_in('up{job=~"localizer.*"} == 0'), {"up"})

    def test_the_dashboard_has_the_panels_the_fleet_needs(self):
        text = " ".join(dashboard_queries())
        for needed in ("localizer_stage_seconds_bucket", "localizer_sessions", "localizer_rejections_total",
                       "localizer_estimates_total", "histogram_quantile(0.99", "backend"):
            self.assertIn(needed, text)


@unittest.skipUnless(ops_util.have_binaries(),
                     f"no localizer binaries (server={ops_util.SERVER!r}, cli={ops_util.CLI!r})")
class AgainstALiveScrapeTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="localizer-dash-")
        cls.server = ops_util.Server(cls.tmp, "instance")
        try:
            ops_util.stream_simulation(cls.server.grpc_target, seconds=3.0)
            cls.exposed = ops_util.metric_names(cls.server.metrics())
        finally:
            cls.server.stop()
            shutil.rmtree(cls.tmp, ignore_errors=True)

    def check(self, queries, what):
        self.assertTrue(queries, f"no queries found in the {what}")
        for expr in queries:
            names = names_in(expr)
            self.assertTrue(names, f"{what} query reads no metric: {expr}")
            missing = names - self.exposed - PROMETHEUS_SERIES
            self.assertFalse(missing, f"{what} query reads {sorted(missing)}, which /metrics does not expose: {expr}")

    def test_every_dashboard_query_reads_exposed_metrics(self):
        self.check(dashboard_queries(), "dashboard")

    def test_every_alert_reads_exposed_metrics(self):
        self.check(alert_queries(), "alert rule")


if __name__ == "__main__":
    unittest.main()
