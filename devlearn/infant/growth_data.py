"""The growth data the body is built from: WHO medians and anthropometric growth curves."""

from __future__ import annotations

import math

WHO_SOURCE = (
    "WHO Child Growth Standards (WHO Multicentre Growth Reference Study Group, 2006), boys, "
    "birth to 2 years, monthly LMS tables, median (M) column: length-for-age (lhfa_boys_0-to-2), "
    "weight-for-age (wfa_boys_0-to-2) and head circumference-for-age (hcfa_boys_0-to-2)"
)
"""Where :data:`WHO_LENGTH_CM`, :data:`WHO_WEIGHT_KG` and :data:`WHO_HEAD_CM` come from. Boys,
because MIMo, whose body ours is, was built as a boy-sized 18-month-old. The medians were
transcribed from public copies of those tables and cross-checked between several independent
ones (the WHO site itself could not be read from where they were written): every value at 0,
6, 12, 18 and 24 months agreed to the fourth decimal."""

WHO_MEDIANS = (
    (49.8842, 3.3464, 34.4618),  # 0
    (54.7244, 4.4709, 37.2759),  # 1
    (58.4249, 5.5675, 39.1285),  # 2
    (61.4292, 6.3762, 40.5135),  # 3
    (63.8860, 7.0023, 41.6317),  # 4
    (65.9026, 7.5105, 42.5576),  # 5
    (67.6236, 7.9340, 43.3306),  # 6
    (69.1645, 8.2970, 43.9803),  # 7
    (70.5994, 8.6151, 44.5300),  # 8
    (71.9687, 8.9014, 44.9998),  # 9
    (73.2812, 9.1649, 45.4051),  # 10
    (74.5388, 9.4122, 45.7573),  # 11
    (75.7488, 9.6479, 46.0661),  # 12
    (76.9186, 9.8749, 46.3395),  # 13
    (78.0497, 10.0953, 46.5844),  # 14
    (79.1458, 10.3108, 46.8060),  # 15
    (80.2113, 10.5228, 47.0088),  # 16
    (81.2487, 10.7319, 47.1962),  # 17
    (82.2587, 10.9385, 47.3711),  # 18
    (83.2418, 11.1430, 47.5357),  # 19
    (84.1996, 11.3462, 47.6919),  # 20
    (85.1348, 11.5486, 47.8408),  # 21
    (86.0477, 11.7504, 47.9833),  # 22
    (86.9410, 11.9514, 48.1201),  # 23
    (87.8161, 12.1515, 48.2515),  # 24
)
"""Median (length cm, weight kg, head circumference cm) of boys at 0, 1, ..., 24 months, one row
a month (the month at the end of each row): length is recumbent (crown to heel, lying)."""

WHO_LENGTH_CM = tuple(row[0] for row in WHO_MEDIANS)
"""Median recumbent length (crown to heel, lying) of boys at 0, 1, ..., 24 months (cm)."""
WHO_WEIGHT_KG = tuple(row[1] for row in WHO_MEDIANS)
"""Median weight of boys at 0, 1, ..., 24 months (kg)."""
WHO_HEAD_CM = tuple(row[2] for row in WHO_MEDIANS)
"""Median head circumference of boys at 0, 1, ..., 24 months (cm)."""

ANTHROKIDS_SOURCE = (
    "AnthroKids (NIST): Snyder, Schneider, Owings, Reynolds, Golomb and Schork (1977), "
    "Anthropometry of infants, children, and youths to age 18 for product safety design, "
    "measurement means of the infant age groups; curves a * ln(age + b) + c fitted by MIMo "
    "v2's authors (trieschlab/MIMo, mimo_infant/growth/data/params.json)"
)
"""Where :data:`ANTHROKIDS_CURVES` come from: the body-part sizes MIMo v2 grows its infant by
(MIMo's code is not used, only these fitted numbers)."""

ANTHROKIDS_CURVES: dict[str, tuple[float, float, float]] = {
    "shoulder_elbow_length": (6.5045706363457585, 15.341494584054242, -6.973972371838398),
    "elbow_hand_length": (6.649244197461142, 10.672098608301102, -1.116669546093675),
    "hand_length": (1.807893920763198, 4.065326075899756, 3.8602500628577907),
    "hand_breadth": (0.5576097173905573, 2.759629199815948, 3.011226156774235),
    "middle_finger_diameter": (1.031915880660834, 1.980374141411991, 6.046550226166198),
    "upper_arm_circumference": (1.1122546914444784, 0.10000000000000002, 11.760055532402925),
    "forearm_circumference": (1.0425480634537803, 0.10000000000000075, 11.800470420518526),
    "hip_breadth": (1.4341760046387282, 0.10499418458476285, 12.989858733010582),
    "rump_knee_length": (2122.3908171324115, 5009.376435062313, -18066.617685980164),
    "knee_sole_length": (18.77345106119117, 36.83828214163621, -52.962767853311384),
    "mid_thigh_circumference": (7.152278614284938, 9.10593915972378, 1.40667810434768),
    "calf_circumference": (2.156721075077345, 0.7477700715477089, 12.567056487136343),
    "foot_length": (6.915336579236893, 21.513614075129805, -13.159730009798846),
    "foot_breadth": (3.137812149969795, 28.236151712915987, -6.896841220624604),
}
"""Body-part size s(age) = a * ln(age + b) + c (cm; the finger's diameter in mm) for age in
months, as (a, b, c). The youngest AnthroKids group's mean age is about a month, so the curves
are extrapolated to birth; those fitted with b below a month (arm, forearm and calf
circumference, hip breadth: b at or near the fit's lower bound, 0.1) fall steeply there, which
:data:`YOUNGEST_MEASURED_MONTHS` keeps out."""

YOUNGEST_MEASURED_MONTHS = 1.0
"""Mean age (months) of AnthroKids' youngest group: below it a curve with b under a month is
not extrapolated (a newborn's arm girth would otherwise drop 25% in its first month, an
artefact of the log fit), it keeps its value at this age."""


def who_median(table: tuple[float, ...], age_months: float) -> float:
    """A WHO median at any age in [0, 24] months, linear between the monthly values."""
    lo = min(int(math.floor(age_months)), len(table) - 2)
    frac = age_months - lo
    return table[lo] + frac * (table[lo + 1] - table[lo])


def who_age_of(table: tuple[float, ...], value: float) -> float:
    """The age (months) at which a rising WHO median reaches ``value`` (linear between months).

    Raises:
        ValueError: ``value`` is outside the table's range.
    """
    if not table[0] <= value <= table[-1]:
        raise ValueError(f"{value} is outside the table's range [{table[0]}, {table[-1]}]")
    for month in range(len(table) - 1):
        if value <= table[month + 1]:
            return month + (value - table[month]) / (table[month + 1] - table[month])
    return float(len(table) - 1)


def anthrokids_size(measure: str, age_months: float) -> float:
    """A body-part size from :data:`ANTHROKIDS_CURVES` at ``age_months`` (its unit); a steep
    curve (b under a month) is held at :data:`YOUNGEST_MEASURED_MONTHS` below that age."""
    a, b, c = ANTHROKIDS_CURVES[measure]
    if b < YOUNGEST_MEASURED_MONTHS:
        age_months = max(age_months, YOUNGEST_MEASURED_MONTHS)
    return a * math.log(age_months + b) + c
