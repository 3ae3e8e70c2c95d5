"""Every predefined OpenCV ArUco dictionary and AprilTag family is accepted by name
(case-insensitive, with or without the DICT_ prefix) and its tags are detected; a bad
name lists the valid ones."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from swarmdeck.tracking import ConfigError, TrackerConfig
from swarmdeck.tracking.calibration import CharucoSpec
from swarmdeck.tracking.detector import MarkerDetector
from swarmdeck.tracking.dictionaries import DICTIONARIES, canonical_dictionary, dictionary

OPENCV_NAMES = sorted(n for n in dir(cv2.aruco) if n.startswith("DICT_") and isinstance(getattr(cv2.aruco, n), int))


def test_every_predefined_opencv_dictionary_has_a_name():
    assert {getattr(cv2.aruco, n) for n in OPENCV_NAMES} == set(DICTIONARIES.values())
    assert len(DICTIONARIES) == 22  # 16 ArUco 4x4..7x7, ARUCO_ORIGINAL, ARUCO_MIP_36h12, 4 AprilTag families
    for n in OPENCV_NAMES:  # OpenCV's own spellings, e.g. DICT_APRILTAG_36h11 and DICT_APRILTAG_36H11
        assert DICTIONARIES[canonical_dictionary(n)] == getattr(cv2.aruco, n)


@pytest.mark.parametrize("spelling, canonical", [
    ("dict_apriltag_36h11", "DICT_APRILTAG_36h11"), ("APRILTAG_16H5", "DICT_APRILTAG_16h5"),
    ("tag25h9", "DICT_APRILTAG_25h9"), ("6x6_1000", "DICT_6X6_1000"), ("DICT_ARUCO_ORIGINAL", "DICT_ARUCO_ORIGINAL"),
    (" Dict_Aruco_Mip_36H12 ", "DICT_ARUCO_MIP_36h12"), ("dict_7x7_50", "DICT_7X7_50"),
])
def test_names_are_case_insensitive_and_canonicalised_in_the_config(spelling, canonical):
    assert canonical_dictionary(spelling) == canonical
    cfg = TrackerConfig(dictionary=spelling)
    assert cfg.dictionary == canonical
    assert TrackerConfig.from_dict(cfg.to_dict()).dictionary == canonical
    assert CharucoSpec(dictionary=spelling).dictionary == canonical


def test_a_bad_name_lists_the_valid_ones():
    with pytest.raises(ConfigError) as exc:
        TrackerConfig(dictionary="DICT_9X9_50")
    msg = str(exc.value)
    assert "'DICT_9X9_50'" in msg and "DICT_APRILTAG_36h11" in msg and "DICT_4X4_1000" in msg
    with pytest.raises(ValueError, match="DICT_ARUCO_ORIGINAL"):
        dictionary("apriltag")


@pytest.mark.parametrize("name", ["DICT_APRILTAG_36h11", "DICT_APRILTAG_16h5", "DICT_7X7_1000", "DICT_ARUCO_MIP_36h12"])
def test_tags_of_the_family_are_detected(name):
    d = dictionary(name.lower())
    ids = [0, 3, d.bytesList.shape[0] - 1]
    img = np.full((240, 720), 255, np.uint8)
    for k, i in enumerate(ids):
        tag = cv2.aruco.generateImageMarker(d, i, 160, borderBits=1)
        img[40:200, 40 + 240 * k:200 + 240 * k] = tag
    det = MarkerDetector(name.lower(), ()).detect(img)
    assert sorted(det.ids.tolist()) == ids
