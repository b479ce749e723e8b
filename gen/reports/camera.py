"""Camera-rate configurations (issue 27) and their table: what a video pipeline can use.

``npstereo report --camera`` synthesises (and with ``--pnr`` places and routes on the ECP5)
census 5x5 and 7x7, box and SGM, at the camera formats below with all D disparities per
clock (R = 1) and at R = 2 (SGM also at R = 4), and writes ``camera.json`` (the sweep's
schema) and ``camera.md`` (:func:`~.tables.camera_markdown`): logic, memory, clock, frames/s and
disparity evaluations per second (W H D fps, the measure the field compares designs by),
beside the published peers.
"""

from ...params import SGM, StereoParams

__all__ = ["CAMERA_FORMATS", "CAMERA_TRANSFORMS", "CAMERA_ROUNDS", "CAMERA_MATCHERS", "PEERS",
           "camera_configurations", "evaluations_per_second"]

#: (width, height, disparity ranges) of the camera formats.
CAMERA_FORMATS = ((640, 480, (64, 128)), (1280, 720, (64, 128)), (1920, 1080, (64,)))
#: (transform, block) of the rows.
CAMERA_TRANSFORMS = (("census", 5), ("census", 7))
#: The rounds of each matcher (SGM, or the 3x3 box): all D disparities per clock, and half
#: of them, the next step down where R = 1 does not fit the device or its clock. SGM also
#: at R = 4: at R = 2 its left path's update has one clock (70.8 MHz at 1280x720, the
#: eleventh session), at R = 4 three, the rate a camera gets from SGM (141-150 MHz at 720p).
CAMERA_ROUNDS = {SGM: (1, 2, 4), 3: (1, 2)}
#: How the matchers of :data:`CAMERA_ROUNDS` are named.
CAMERA_MATCHERS = {SGM: "SGM", 3: "the 3x3 box"}
#: Published designs: (design, W, H, D, frames/s); Vitis at 200 MHz evaluates 16
#: disparities per clock (24.1 frames/s at 1080p, D = 64).
PEERS = (("Vitis Vision SemiGlobalBM (200 MHz)", 1920, 1080, 64, 24.1),
         ("FP-Stereo", 1242, 374, 64, 161),
         ("Wang et al. 2015 (AD-census + SGM)", 1600, 1200, 128, 42),
         ("Grabowski & Kryjak 2023 (4 pixels per clock)", 3840, 2160, 64, 30))


def evaluations_per_second(width, height, disparities, fps):
    return width * height * disparities * fps


def camera_configurations():
    """Every configuration of the camera sweep: SGM first (the matcher the rates are for),
    then the box, smaller frames first."""
    return [StereoParams(transform=t, block=b, disparities=d, rounds=r, aggregation=a,
                         width=w, height=h)
            for a, rounds in CAMERA_ROUNDS.items() for w, h, ranges in CAMERA_FORMATS
            for d in ranges for t, b in CAMERA_TRANSFORMS for r in rounds]
