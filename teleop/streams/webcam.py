"""Webcam input through MediaPipe Hands (optional extra, not part of the core install).

MediaPipe's hand landmarker (Tasks API) needs two things b2d does not ship: the ``mediapipe``
package, which requires ``opencv-contrib-python`` and so clashes with the core's
``opencv-python-headless`` (both install ``cv2``: use a separate environment), and its model file
``hand_landmarker.task``, which the user downloads from MediaPipe's model page and passes by path.
Both are checked when the adapter is created, with an error that names what is missing.

A webcam gives keypoints only: MediaPipe's world landmarks are metric but centred on the hand, so
they carry no wrist position; wrist poses come from a tracker (``CombinedStream``).
``landmarks_to_frame`` is the pure conversion, tested through generated landmarks.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from .frame import NUM_KEYPOINTS, OperatorFrame, to_wrist_frame


class WebcamUnavailable(RuntimeError):
    """The optional webcam dependencies (package, model file or camera) are missing."""


def landmarks_to_frame(timestamp_ns: int, hands: list[tuple[str, np.ndarray]]) -> OperatorFrame:
    """MediaPipe results -> operator frame. ``hands``: (handedness label 'Left'/'Right', (21, 3)
    world landmarks in metres) per detected hand, label and landmarks both of the person's real
    hand (``WebcamHandStream`` detects on the mirrored image MediaPipe's labels assume, then
    reflects the landmarks back)."""
    frame = OperatorFrame.empty(timestamp_ns)
    for label, points in hands:
        side = label.strip().lower()
        if side not in ("left", "right"):
            raise ValueError(f"handedness label: expected 'Left' or 'Right', got {label!r}")
        points = np.asarray(points, float)
        if points.shape != (NUM_KEYPOINTS, 3):
            raise ValueError(f"landmarks: expected shape ({NUM_KEYPOINTS}, 3), got {points.shape}")
        try:
            kp, _, _ = to_wrist_frame(points, side)
        except ValueError:
            # collapsed or non-finite landmarks: pass them on as non-finite keypoints, as the Manus
            # adapter does, so the sanitizer holds the last good ones instead of the session stopping
            kp = np.full((NUM_KEYPOINTS, 3), np.nan)
        frame = frame.with_hand(side, keypoints=kp)
    return frame


class WebcamHandStream:
    """Keypoints of up to two hands from a camera, one detection per ``poll()``."""

    def __init__(self, model_path: str | Path, camera: int | str = 0, num_hands: int = 2):
        model_path = Path(model_path)
        if not model_path.is_file():
            raise WebcamUnavailable(
                f"MediaPipe hand landmarker model not found at {model_path} (field 'model_path'): download "
                f"'hand_landmarker.task' from MediaPipe's hand landmarker model page and pass its path")
        try:
            import mediapipe as mp
            from mediapipe.tasks.python import BaseOptions
            from mediapipe.tasks.python.vision import HandLandmarker, HandLandmarkerOptions, RunningMode
        except ImportError as exc:
            raise WebcamUnavailable(
                f"webcam input needs the optional package 'mediapipe' ({exc}); install it in a separate "
                f"environment with opencv-contrib-python (it conflicts with opencv-python-headless)") from None
        import cv2

        self._mp, self._cv2 = mp, cv2
        self.capture = cv2.VideoCapture(camera)
        if not self.capture.isOpened():
            raise WebcamUnavailable(f"camera {camera!r} could not be opened (field 'camera')")
        options = HandLandmarkerOptions(base_options=BaseOptions(model_asset_path=str(model_path)),
                                        running_mode=RunningMode.VIDEO, num_hands=num_hands)
        self.landmarker = HandLandmarker.create_from_options(options)
        self._t0 = time.monotonic_ns()

    def poll(self) -> OperatorFrame | None:
        ok, image = self.capture.read()
        if not ok:
            return None
        t_ns = time.monotonic_ns()
        rgb = self._cv2.cvtColor(self._cv2.flip(image, 1), self._cv2.COLOR_BGR2RGB)   # selfie view
        result = self.landmarker.detect_for_video(self._mp.Image(image_format=self._mp.ImageFormat.SRGB, data=rgb),
                                                  (t_ns - self._t0) // 1_000_000)
        # landmarks of the mirrored image describe a reflected hand: negate x to get the real one
        hands = [(h[0].category_name, np.array([[-p.x, p.y, p.z] for p in world]))
                 for h, world in zip(result.handedness, result.hand_world_landmarks)]
        return landmarks_to_frame(t_ns, hands)

    def close(self) -> None:
        self.landmarker.close()
        self.capture.release()
