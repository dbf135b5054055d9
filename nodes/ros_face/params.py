"""The planner's settings as ROS 2 parameters, pure: rcl_interfaces requests -> our params query.

:class:`ParamServer` answers the six parameter services rclcpp gives every node
(``<node>/list_parameters``, ``get_parameters``, ``get_parameter_types``,
``describe_parameters``, ``set_parameters``, ``set_parameters_atomically``; their types:
:mod:`common.ros2_interfaces`) for the ROS node ``/papf_planner``, by asking the running
planner through our own parameter query (``<ns>/planner/params``, JSON,
:mod:`nodes.planner.params`) with the function it is given. So ``ros2 param list|get|set``,
``rqt_reconfigure`` and launch-time tools see the planner's settings by the names
``papf param`` uses (``apf.v_max``, ``papf.lambda_m`` …).

Checks and signatures are ``papf param``'s: a set goes to the planner as the same signed
request (the face holds the run's key and signs each one with a fresh nonce), and the
planner checks it against the declared range and the safety floors before it changes
anything; what it refuses comes back as ROS 2's own ``SetParametersResult(successful=false,
reason)``. Types are ROS's: a double setting takes a double (or an integer), an integer an
integer, a bool a bool, a string a string; arrays and undeclaring are refused. Descriptors
carry the range (``floating_point_range``/``integer_range`` where both ends are bounded),
the range in words (``additional_constraints``, open ends included), the unit and whether
the setting is a safety one, and ``read_only`` when the face takes no changes (a lockstep
``papf run``: runs stay deterministic, as with goals).
"""

from __future__ import annotations

import math

import numpy as np

from common import ros2_interfaces as ri
from common.errors import ConfigError, SchemaError
from common.params import unknown_name

NOT_SET, BOOL, INTEGER, DOUBLE, STRING = range(5)
KIND_TYPE = {"bool": BOOL, "int": INTEGER, "float": DOUBLE, "str": STRING}
DEPTH_RECURSIVE = 0
SRV = "rcl_interfaces/srv/"
READ_ONLY_WHY = ("read-only: this lockstep run keeps its settings (runs stay deterministic); "
                 "use papf launch or papf run --realtime")


class ParamServer:
    """``handle(service, request_cdr)`` -> (response CDR, names changed).

    ``ask(request: dict, signed: bool) -> dict``: our planner's reply to a params request
    (``{"describe": true}`` or ``{"set": [...]}``), ConfigError when it does not answer;
    ``writable``: whether sets are passed on at all.
    """

    def __init__(self, ask, writable: bool, distro: str = ri.DEFAULT_DISTRO):
        self.ask, self.writable, self.distro = ask, writable, distro
        self._specs: dict | None = None

    def specs(self) -> dict:
        """Each setting's type and range (asked once: they do not change in a run)."""
        if self._specs is None:
            self._specs = self.ask({"describe": True}, False).get("specs") or {}
        return self._specs

    def handle(self, service: str, data: bytes) -> tuple[bytes, list[str]]:
        """One request of ``service`` (``list_parameters`` …) -> (response CDR, changed)."""
        typename = ri.PARAM_SERVICES[service]
        try:
            req = ri.deserialize(data, f"{typename}_Request", self.distro)
        except Exception as exc:   # rosbags raises struct/index errors on garbage
            raise SchemaError(f"{service}: {len(data)} bytes are not a {typename} request "
                              f"({type(exc).__name__})") from None
        response, changed = getattr(self, "_" + service)(req)
        return ri.serialize(response, f"{typename}_Response", self.distro), changed

    # -- the services -----------------------------------------------------------------------------
    def _list_parameters(self, req):
        names = sorted(self.ask({}, False)["params"])
        chosen, prefixes = list_names(names, list(req.prefixes), int(req.depth))
        result = self._c("rcl_interfaces/msg/ListParametersResult")(names=chosen, prefixes=prefixes)
        return self._c(f"{SRV}ListParameters_Response")(result=result), []

    def _get_parameters(self, req):
        params = self.ask({}, False)["params"]
        values = [self._value(params.get(n), self.specs().get(n)) for n in req.names]
        return self._c(f"{SRV}GetParameters_Response")(values=values), []

    def _get_parameter_types(self, req):
        specs = self.specs()
        types = [KIND_TYPE.get(specs[n]["kind"], NOT_SET) if n in specs else NOT_SET
                 for n in req.names]
        return self._c(f"{SRV}GetParameterTypes_Response")(types=np.array(types, np.uint8)), []

    def _describe_parameters(self, req):
        specs = self.specs()
        out = [self._descriptor(n, specs[n]) for n in req.names if n in specs]
        return self._c(f"{SRV}DescribeParameters_Response")(descriptors=out), []

    def _set_parameters(self, req):
        results, changed = [], []
        for p in req.parameters:   # each on its own, as rclcpp's set_parameters service does
            ok, why, names = self._set([p])
            results.append(self._result(ok, why))
            changed += names
        return self._c(f"{SRV}SetParameters_Response")(results=results), changed

    def _set_parameters_atomically(self, req):
        ok, why, names = self._set(list(req.parameters))
        return self._c(f"{SRV}SetParametersAtomically_Response")(result=self._result(ok, why)), names

    # -- helpers ----------------------------------------------------------------------------------
    def _set(self, params: list) -> tuple[bool, str, list[str]]:
        """Pass ``params`` to the planner as one signed request: (successful, reason, names)."""
        if not self.writable:
            return False, READ_ONLY_WHY, []
        names = ", ".join(p.name for p in params)
        try:
            sets = [f"{p.name}={self._text(p)}" for p in params]
            reply = self.ask({"set": sets}, True)
        except ConfigError as exc:
            return False, str(exc), []
        if reply.get("error"):   # the planner's range and safety checks said no
            return False, f"{names} refused by the planner: {reply['error']}", []
        return True, "", [p.name for p in params]

    def _text(self, p) -> str:
        """A ROS Parameter's value as our ``--set`` text; ConfigError on a type ROS would refuse."""
        specs = self.specs()
        if p.name not in specs:
            raise unknown_name(p.name, specs, "planner parameter")
        kind, v = specs[p.name]["kind"], p.value
        want = KIND_TYPE[kind]
        if v.type == NOT_SET:
            raise ConfigError(f"{p.name}: parameters of the planner cannot be undeclared")
        if v.type != want and not (want == DOUBLE and v.type == INTEGER):
            raise ConfigError(f"{p.name} is a {_TYPE_NAMES[want]} parameter, not "
                              f"{_TYPE_NAMES.get(v.type, f'type {v.type}')} "
                              f"({specs[p.name]['valid']})")
        if v.type == BOOL:
            return "true" if v.bool_value else "false"
        if v.type == INTEGER:
            return str(int(v.integer_value))
        if v.type == DOUBLE:
            return repr(float(v.double_value))
        return str(v.string_value)

    def _c(self, typename: str):
        return ri.msg_class(typename, self.distro)

    def _result(self, ok: bool, why: str):
        return self._c("rcl_interfaces/msg/SetParametersResult")(successful=ok, reason=why)

    def _value(self, value, spec: dict | None):
        """A ParameterValue of one of our values (NOT_SET for an unknown name)."""
        kind = KIND_TYPE.get(spec["kind"], NOT_SET) if spec else NOT_SET
        v = dict(type=NOT_SET, bool_value=False, integer_value=0, double_value=0.0,
                 string_value="", byte_array_value=np.zeros(0, np.uint8),
                 bool_array_value=np.zeros(0, bool), integer_array_value=np.zeros(0, np.int64),
                 double_array_value=np.zeros(0, np.float64), string_array_value=[])
        if value is not None and kind != NOT_SET:
            v["type"] = kind
            field = {BOOL: "bool_value", INTEGER: "integer_value", DOUBLE: "double_value",
                     STRING: "string_value"}[kind]
            v[field] = {BOOL: bool, INTEGER: int, DOUBLE: float, STRING: str}[kind](value)
        return self._c("rcl_interfaces/msg/ParameterValue")(**v)

    def _descriptor(self, name: str, spec: dict):
        c = ri.typestore(self.distro).types
        kind = KIND_TYPE.get(spec["kind"], NOT_SET)
        lo, hi = spec.get("lo"), spec.get("hi")
        bounded = lo is not None and hi is not None and math.isfinite(lo) and math.isfinite(hi)
        fp = [c["rcl_interfaces/msg/FloatingPointRange"](from_value=float(lo), to_value=float(hi),
                                                          step=0.0)] if bounded and kind == DOUBLE else []
        ir = [c["rcl_interfaces/msg/IntegerRange"](from_value=int(lo), to_value=int(hi), step=1)
              ] if bounded and kind == INTEGER else []
        what = f"{'safety setting; ' if spec.get('safety') else ''}{spec.get('valid', '')}"
        return c["rcl_interfaces/msg/ParameterDescriptor"](
            name=name, type=kind, description=f"planner setting {name}"
            + (f" [{spec['unit']}]" if spec.get("unit") else ""),
            additional_constraints=what, read_only=not self.writable, dynamic_typing=False,
            floating_point_range=fp, integer_range=ir)

    def event(self, names: list[str], node: str, stamp_ns: int) -> bytes:
        """rcl_interfaces/ParameterEvent of ``names`` changed on ``node`` (their new values)."""
        c = ri.typestore(self.distro).types
        params = self.ask({}, False)["params"]
        changed = [c["rcl_interfaces/msg/Parameter"](name=n, value=self._value(
            params.get(n), self.specs().get(n))) for n in names]
        sec, nsec = divmod(int(stamp_ns), 10**9)
        msg = c["rcl_interfaces/msg/ParameterEvent"](
            stamp=c["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec), node=node,
            new_parameters=[], changed_parameters=changed, deleted_parameters=[])
        return ri.serialize(msg, "rcl_interfaces/msg/ParameterEvent", self.distro)


_TYPE_NAMES = {NOT_SET: "not set", BOOL: "bool", INTEGER: "integer", DOUBLE: "double",
               STRING: "string", 5: "byte array", 6: "bool array", 7: "integer array",
               8: "double array", 9: "string array"}


def list_names(names: list[str], prefixes: list[str], depth: int) -> tuple[list[str], list[str]]:
    """rclcpp's ``list_parameters``: the names under ``prefixes`` (all without any) at most
    ``depth`` levels deep (0: every level), and the prefixes (namespaces) of those listed."""
    chosen, found = [], []
    for name in names:
        everything = not prefixes and (depth == DEPTH_RECURSIVE or name.count(".") < depth)
        under = any(name == p or (name.startswith(p + ".") and (
            depth == DEPTH_RECURSIVE or name[len(p):].count(".") < depth)) for p in prefixes)
        if everything or under:
            chosen.append(name)
            ns = name.rpartition(".")[0]
            if ns and ns not in found:
                found.append(ns)
    return chosen, found
