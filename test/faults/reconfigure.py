#!/usr/bin/python3
"""dynamic_reconfigure values out of range sent to a running gear_simulator: above the maximum,
below the minimum, +-inf and NaN for every parameter the server describes (the ranges come from
the server's own description, i.e. config/Simulator.cfg). One rule for a bad value, at start and at
run time: it is refused. The server must answer with the value in effect (kept), the node must log
the refusal naming the parameter, and it must keep running: states still arrive, carrying the mu and
sigma in effect."""
import math
import subprocess
import tempfile

import faultlib as fl

MODEL = ("gear_pair.yaml", "load.yaml", "run.yaml", "simulator.yaml")
# Real time at 1000 states per second (a request's effect shows within milliseconds), run on
# forever, no clock or scalar topics.
SIMULATOR = {"real_time_factor": 1.0, "t_end": 0.0, "loop": False, "paused": False, "publish_clock": False,
             "publish_scalars": False, "publish_rate": 1000.0}
TIMEOUT = 20.0


class Watch:
    """The node's /rosout messages and its latest GearState."""

    def __init__(self, node):
        import rospy
        from gear_dynamics.msg import GearState
        from rosgraph_msgs.msg import Log
        self.node, self.logs, self.state = node, [], None
        rospy.Subscriber("/rosout", Log, lambda m: self.logs.append(m.msg) if m.name == "/" + node else None)
        rospy.Subscriber("/state", GearState, self._state, queue_size=1)

    def _state(self, m):
        self.state = m

    def wait(self, condition, what):
        fl.wait_until(condition, TIMEOUT, what)


def requests(description):
    """(parameter, case, value, expected value or None for 'the one in effect')."""
    out = []
    for d in description:
        lo, hi, name = d["min"], d["max"], d["name"]
        if d["type"] not in ("double", "int"):
            continue
        span = max(abs(hi - lo), 1.0)
        out += [(name, "above_max", hi + span, None), (name, "below_min", lo - span, None)]
        if d["type"] == "double":
            out += [(name, "plus_inf", math.inf, None), (name, "minus_inf", -math.inf, None), (name, "nan", math.nan, None)]
    return out


def run(suite):
    import dynamic_reconfigure.client
    import rospy
    rospy.init_node("fault_reconfigure", anonymous=True, disable_signals=True)
    params = fl.load_yaml(*[fl.config_file(f) for f in MODEL])
    params["simulator"].update(SIMULATOR)
    node = fl.node_name("simulator")
    watch = Watch(node)
    log = tempfile.TemporaryFile("w+")
    process = fl.start_node("gear_simulator", node, params, output=log)

    def node_output():
        log.seek(0)
        return log.read()[-5000:]

    try:
        client = dynamic_reconfigure.client.Client("/" + node, timeout=TIMEOUT)
        initial = client.get_configuration(timeout=TIMEOUT)
        assert initial is not None, "no configuration from gear_simulator within %g s:\n%s" % (TIMEOUT, node_output())
        current = dict(initial)  # in effect, as the server last answered
        for param, how, value, expected in requests(client.get_parameter_descriptions()):
            if process.poll() is not None:
                raise AssertionError("gear_simulator ended (exit %s):\n%s" % (process.returncode, node_output()))
            with suite.case("reconfigure_out_of_range", param + "_" + how):
                logs = len(watch.logs)
                want = current[param] if expected is None else expected
                current = client.update_configuration({param: value})
                answer = current[param]
                assert answer == want, "%s = %r: the server answered %r, expected %r" % (param, value, answer, want)
                said = "%s = " % param
                logged = lambda: [m for m in watch.logs[logs:] if said in m and "refused" in m and "keeping" in m]
                watch.wait(logged, "log line on %s = %r" % (param, value))
                assert process.poll() is None, "the node ended (exit %s)" % process.returncode
                t0 = watch.state.t if watch.state else -1.0
                watch.wait(lambda: watch.state is not None and watch.state.t > t0, "new state")
                if param in ("mu", "sigma"):
                    watch.wait(lambda: getattr(watch.state, param) == want, "state with %s = %r" % (param, want))
                assert all(math.isfinite(x) for x in (watch.state.delta, watch.state.delta_dot, watch.state.phi))
                print("  %s = %r -> %r; logged: %s" % (param, value, answer, logged()[0]))
                current = client.update_configuration({param: initial[param]})
                assert current[param] == initial[param]
    finally:
        process.terminate()
        try:
            process.wait(10)
        except subprocess.TimeoutExpired:
            process.kill()


if __name__ == "__main__":
    fl.main(run)
