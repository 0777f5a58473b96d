"""Controller exports of one set of compensation parameters (Siemens 840D, Beckhoff TwinCAT) and their headers."""

from __future__ import annotations

from thermaxis.compensation.model import CONVENTION, TENTHS_UM_PER_MM, UM_PER_MM
from thermaxis.compensation.runtime import ControllerParameters
from thermaxis.method.decouple import MM_PER_M

__all__ = [
    "siemens_840d",
    "twincat",
    "file_header",
]


# --------------------------------------------------------------------------- controller units


def siemens_840d(p: ControllerParameters) -> list[tuple[str, str, float, str]]:
    """(parameter, name, value, unit) rows of SINUMERIK 840D setting data; SD43900 alone when offset only."""
    rows = [("SD43900", "TEMP_COMP_ABS_VALUE", p.k0_mm, "mm")]
    if not p.offset_only:
        rows += [
            ("SD43910", "TEMP_COMP_SLOPE", p.tan_beta, "dimensionless (mm/mm)"),
            ("SD43920", "TEMP_COMP_REF_POSITION", p.p0_mm, "mm"),
        ]
    return rows


def twincat(p: ControllerParameters) -> list[tuple[str, str, float, str]]:
    """(parameter, name, value, unit) rows of TwinCAT CNC axis parameters (before rounding to SGN32)."""
    return [
        ("P-AXIS-00272", "temp_comp_position_0", p.p0_mm * TENTHS_UM_PER_MM, "0.1 um"),
        ("P-AXIS-00273", "temp_comp_offset_0", p.k0_mm * TENTHS_UM_PER_MM, "0.1 um"),
        ("P-AXIS-00274", "temp_comp_coefficient", p.tan_beta * UM_PER_MM * MM_PER_M, "um/m"),
    ]


def file_header(kind: str, statement: str) -> str:
    """The comment block every compensation CSV starts with (read them with ``comment='#'``)."""
    lines = [f"thermaxis compensation: {kind}", statement, f"Convention: {CONVENTION}."] + HEADERS[
        kind
    ]
    return "".join(f"# {line}\n" for line in lines)


HEADERS = {
    "siemens_840d": [
        "SINUMERIK 840D setting data per measurement of each held-out run, from that fold's model after the fallback policy;",
        "final_model_value: the model fitted on all runs, same temperatures. SD43900 TEMP_COMP_ABS_VALUE K0 [mm];",
        "SD43910 TEMP_COMP_SLOPE tan(beta) [dimensionless, mm/mm]; SD43920 TEMP_COMP_REF_POSITION P0 [mm].",
        "Source: SINUMERIK Function Manual Extended Functions K3 Compensations 03/2013 (6FC5397-1BP40-3BA1) sec. 4.2:",
        "compensation value = K0 + tan(beta) * (Px - P0); tan(beta)(T) = (T - T0) * TK_max * 1e-6 / (Tmax - T0) with TK in um/m,",
        "i.e. tan(beta) is dimensionless (not per mil). MD32750 TEMP_COMP_TYPE activates it (1 = position-independent only).",
    ],
    "twincat": [
        "TwinCAT CNC axis parameters per measurement of each held-out run, from that fold's model after the fallback policy;",
        "final_model_value: the model fitted on all runs, same temperatures. P-AXIS-00272 temp_comp_position_0 [0.1 um];",
        "P-AXIS-00273 temp_comp_offset_0 [0.1 um]; P-AXIS-00274 temp_comp_coefficient [um/m]; register: rounded for SGN32.",
        "Source: Beckhoff TwinCAT CNC axis parameters P-AXIS-00272/00273/00274 (infosys.beckhoff.com, tccncaxisparameter),",
        "activated by lr_param.temp_comp 1 (P-AXIS-00271), adjusted by the PLC.",
    ],
    "residuals": [
        "Per fold (held-out run), measurement, direction and target: uncompensated_um = deviation minus the static pitch table",
        "(the run's first measurement, mean of its passes); compensation_um from the exported K0, tan(beta), P0 after limits;",
        "residual_um = uncompensated_um + compensation_um (um).",
    ],
    "iso230_2": [
        "ISO 230-2 quantities one bidirectional pass supports (E_up, E_down, E, M, B; um) before and after compensation;",
        "rows with computed = False need repeated approaches and are not computed.",
    ],
    "summary": [
        "Per fold and measurement: largest |deviation| over the stroke and both directions, and E, before and after compensation (um);",
        "status ok / hold / ramp with the fallback reasons.",
    ],
}
