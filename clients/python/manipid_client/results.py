"""RobotResult: a URDF robot identification's result, keyed by name.

The service returns the result as JSON lists (base parameters in order, friction per joint in
order); lab scripts want to write result.base_parameters["fv2"]. RobotResult reads the same
JSON (its `data`) and gives it by name; nothing is computed here that the server did not send,
except base_values(), which evaluates the base parameters' printed combinations.
"""
from __future__ import annotations

import re
from typing import Any, Dict, List, Mapping, NamedTuple, Optional

# One term of a base parameter's name: "Izz1", " + Iyy2", " - 0.316*m3", " + 1.2e-05*mz4".
_TERM = re.compile(r"\s*([+-])?\s*(?:([0-9.]+(?:[eE][+-]?[0-9]+)?)\s*\*\s*)?([A-Za-z]+[0-9]+)\s*")


class Estimate(NamedTuple):
    """One base parameter's estimate and its standard error (None when the data give none).
    A tuple: `value, std_error = result.base_parameters["fv2"]`."""

    estimate: Optional[float]
    std_error: Optional[float]


class RobotResult:
    """The result of a robot identification (Job.robot_result(), or RobotResult(job.wait())).

    By name:
      base_parameters  {name: Estimate(estimate, std_error)}, in the server's order. A name is
                       a standard parameter ("fv2", "mx7") or the combination the data determine
                       ("my2 - 0.316*m3 - mz3 - ..."): the base parameters of the robot;
      friction         {joint name: {"fv": ..., "fc": ..., "fo": ..., "Ia": ...}} (the terms
                       identified);
      point            {standard parameter: value}: every link's m, mx..mz, Ixx..Izz and the
                       friction, the estimate nearest to the URDF's values (what /urdf writes);
      prior            {standard parameter: value}: the URDF's own values;
      data_share       {base parameter: the share of its estimate the data determine, 0..1}
                       (the rest is the URDF's value);
      validation       the validation runs' figures under the judge (relative_error and rms_error
                       per fitted joint, overall_relative_error, and "prior": the same for the
                       URDF's values), or None without a validation run;
      fit              the identification runs' figures (residual_rms, relative_error, rms_error
                       per fitted joint, overall_relative_error), under the judge;
      judge            {"lowpass", "cutoff_hz", "trim_seconds"}: what every figure is judged under;
      selection        what held-out prediction chose ("ridge", "held_out_error", "candidates");
      warnings, unexcited, unidentifiable, condition_number, torque_joints, robot_id, dataset_id.
    `data` is the whole JSON; result["key"] reads it too.
    """

    def __init__(self, result: Mapping[str, Any]) -> None:
        if "base_parameters" not in result:
            raise ValueError("not a robot identification's result (no base_parameters): "
                             "identify(..., robot=...) makes one")
        self.data: dict = dict(result)

    def __getitem__(self, key: str) -> Any:
        return self.data[key]

    def __repr__(self) -> str:
        return (f"<RobotResult {self.data.get('robot', {}).get('name')}: {len(self.data['base_parameters'])} base "
                f"parameters>")

    @property
    def base_parameters(self) -> Dict[str, Estimate]:
        return {entry["name"]: Estimate(entry.get("estimate"), entry.get("std_error"))
                for entry in self.data["base_parameters"]}

    @property
    def friction(self) -> Dict[str, Dict[str, float]]:
        return {entry["joint"]: {key: value for key, value in entry.items() if key != "joint"}
                for entry in self.data.get("friction", [])}

    @property
    def point(self) -> Dict[str, float]:
        return dict(self.data.get("point", {}))

    @property
    def prior(self) -> Dict[str, float]:
        return dict(self.data.get("prior", {}))

    @property
    def data_share(self) -> Dict[str, Optional[float]]:
        return {entry["name"]: entry.get("data_share") for entry in self.data["base_parameters"]}

    @property
    def judge(self) -> dict:
        return dict(self.data.get("judge", {}))

    @property
    def selection(self) -> dict:
        return dict(self.data.get("selection", {}))

    @property
    def torque_joints(self) -> List[str]:
        return list(self.data.get("torque_joints", []))

    @property
    def validation(self) -> Optional[dict]:
        return self.data.get("validation")

    @property
    def fit(self) -> dict:
        return dict(self.data.get("fit", {}))

    @property
    def warnings(self) -> List[str]:
        return list(self.data.get("warnings", []))

    @property
    def unexcited(self) -> List[str]:
        return list(self.data.get("unexcited", []))

    @property
    def unidentifiable(self) -> List[str]:
        return list(self.data.get("unidentifiable", []))

    @property
    def condition_number(self) -> Optional[float]:
        return self.data.get("condition_number")

    @property
    def robot_id(self) -> Optional[str]:
        return self.data.get("robot_id")

    @property
    def dataset_id(self) -> Optional[str]:
        return self.data.get("dataset_id")

    def base_values(self, values: Optional[Mapping[str, float]] = None) -> Dict[str, float]:
        """Each base parameter evaluated at standard parameter values by name — by default the
        URDF's (`prior`), to set the estimate beside what the CAD model says; or a simulation's
        truth. Parameters missing from `values` are taken from the prior. The combinations'
        coefficients are the ones printed in the names (6 significant digits)."""
        at = self.prior
        at.update(values or {})
        return {name: base_value(name, at) for name in self.base_parameters}


def base_value(name: str, values: Mapping[str, float]) -> float:
    """A base parameter's name ("Izz2 + 0.099856*m3 - mz3") evaluated at standard parameter
    values by name. ValueError for a name that is not such a combination or a parameter that
    `values` lacks."""
    total = 0.0
    position = 0
    first = True
    while position < len(name):
        match = _TERM.match(name, position)
        if not match or match.end() == position or (match.group(1) is None and not first):
            raise ValueError(f"cannot read base parameter {name!r} at character {position}")
        sign, coefficient, parameter = match.groups()
        if parameter not in values:
            raise ValueError(f"base parameter {name!r} needs {parameter}, which the values lack")
        term = float(coefficient) * values[parameter] if coefficient else values[parameter]
        total += -term if sign == "-" else term
        position = match.end()
        first = False
    if first:
        raise ValueError("an empty base parameter name")
    return total
