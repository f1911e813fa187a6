# SPDX-License-Identifier: Apache-2.0
"""ROS 2 messages for tools/export.py: headers, planar poses, and the markers of the
global map and of the ground truth (visualization_msgs/msg/Marker). Built with a
rosbags typestore; every field a caller does not set gets its type's zero value, so
the same code fills the Marker of any ROS 2 distribution.

Frames: `map` is the world frame W of the LCM messages (x, y [m], theta [rad]
about z); z = 0 throughout.
"""
import math

# Marker colours (r, g, b): the global map's statuses and the ground truth.
STATIC = (0.13, 0.65, 0.25)       # in the global map (global_landmark_t.STATIC)
MOVING = (0.85, 0.10, 0.10)       # moving, a DYNAMIC_NOTICE went out (global_map_t.moving_by > 0)
UNCONFIRMED = (1.00, 0.60, 0.00)  # moving, unconfirmed: no notice yet (moving_by == 0)
TRUTH_STATIC = (0.55, 0.55, 0.55)
TRUTH_MOVING = (0.75, 0.20, 0.80)
LANDMARK_DIAMETER_M = 0.25
ELLIPSE_SIGMA = 3.0               # semi-axes: 3 standard deviations along the covariance's principal axes
ELLIPSE_ALPHA = 0.3
ELLIPSE_THICKNESS_M = 0.01
MIN_SCALE_M = 1e-3                # a marker of zero size is refused by RViz


class MarkerMaker:
    """Message constructors over one typestore (its `types` by name in T)."""

    def __init__(self, typestore):
        import numpy
        self.np = numpy
        self.ts = typestore
        self.T = typestore.types
        self._zeros = {}
        Marker = self.T["visualization_msgs/msg/Marker"]
        self.ARROW, self.SPHERE, self.CYLINDER, self.SPHERE_LIST = (Marker.ARROW, Marker.SPHERE, Marker.CYLINDER,
                                                                    Marker.SPHERE_LIST)
        self.ADD, self.DELETE = Marker.ADD, Marker.DELETE

    def zero(self, msgtype):
        """The fields of `msgtype` at their zero values (cached: never mutate what it returns)."""
        if msgtype not in self._zeros:
            self._zeros[msgtype] = {name: self._zero_of(desc) for name, desc in self.ts.get_msgdef(msgtype).fields}
        return self._zeros[msgtype]

    def _zero_of(self, desc):
        kind, spec = desc  # rosbags Nodetype: 1 BASE, 2 NAME, 3 ARRAY, 4 SEQUENCE
        kind = int(kind)
        if kind == 1:
            base = spec[0]
            return "" if base in ("string", "wstring") else False if base == "bool" else 0.0 if base.startswith("float") else 0
        if kind == 2:
            return self.T[spec](**self.zero(spec))
        inner, count = spec
        if int(inner[0]) == 1 and inner[1][0] not in ("string", "wstring"):
            dtype = {"bool": bool, "byte": self.np.uint8, "char": self.np.uint8}.get(inner[1][0], inner[1][0])
            return self.np.zeros(count if kind == 3 else 0, dtype=dtype)
        return [self._zero_of(inner) for _ in range(count)] if kind == 3 else []

    def make(self, msgtype, **fields):
        return self.T[msgtype](**{**self.zero(msgtype), **fields})

    def header(self, t, frame="map"):
        return self.T["std_msgs/msg/Header"](stamp=self.T["builtin_interfaces/msg/Time"](sec=t[0], nanosec=t[1]),
                                             frame_id=frame)

    def vec3(self, x, y, z):
        return self.T["geometry_msgs/msg/Vector3"](x=float(x), y=float(y), z=float(z))

    def point(self, x, y, z=0.0):
        return self.T["geometry_msgs/msg/Point"](x=float(x), y=float(y), z=float(z))

    def yaw(self, theta):
        """Rotation by theta [rad] about z as a unit quaternion."""
        return self.T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=math.sin(0.5 * theta), w=math.cos(0.5 * theta))

    def pose2d(self, x, y, theta):
        return self.T["geometry_msgs/msg/Pose"](position=self.point(x, y), orientation=self.yaw(theta))

    def color(self, rgb, a=1.0):
        return self.T["std_msgs/msg/ColorRGBA"](r=rgb[0], g=rgb[1], b=rgb[2], a=a)

    def marker(self, header, ns, mid, kind, action=None, **fields):
        return self.make("visualization_msgs/msg/Marker", header=header, ns=ns, id=int(mid), type=kind,
                         action=self.ADD if action is None else action, **fields)

    def delete(self, header, ns, mid):
        return self.marker(header, ns, mid, self.SPHERE, self.DELETE)

    def array(self, markers):
        return self.T["visualization_msgs/msg/MarkerArray"](markers=markers)

    def truth_markers(self, gt, header):
        """The true landmarks of a ground_truth_t: two sphere lists (ns truth_landmarks, id 0
        static, id 1 moving), so that one message holds the world's 72 or 7,000 landmarks."""
        static, moving = [], []
        for lm in gt.landmarks[:max(0, min(gt.num_landmarks, len(gt.landmarks)))]:
            (moving if lm.moving else static).append(self.point(lm.x, lm.y))
        d = LANDMARK_DIAMETER_M
        return self.array([self.marker(header, "truth_landmarks", i, self.SPHERE_LIST, points=pts,
                                       pose=self.pose2d(0, 0, 0), scale=self.vec3(d, d, d), color=self.color(rgb))
                           for i, (pts, rgb) in enumerate(((static, TRUTH_STATIC), (moving, TRUTH_MOVING)))])


def ellipse(cxx, cxy, cyy):
    """(major, minor diameters [m], angle of the major axis [rad]) of the ELLIPSE_SIGMA
    ellipse of a 2x2 covariance [m^2]; None when it is not a finite, non-negative one."""
    if not all(math.isfinite(v) for v in (cxx, cxy, cyy)):
        return None
    mid, half = 0.5 * (cxx + cyy), math.hypot(0.5 * (cxx - cyy), cxy)
    l1, l2 = mid + half, mid - half
    if l2 < -1e-12 * max(1.0, abs(l1)):
        return None
    k = 2.0 * ELLIPSE_SIGMA
    return (max(k * math.sqrt(max(l1, 0.0)), MIN_SCALE_M), max(k * math.sqrt(max(l2, 0.0)), MIN_SCALE_M),
            0.5 * math.atan2(2.0 * cxy, cxx - cyy))


class GlobalMapMarkers:
    """GLOBAL_MAP chunks as MarkerArrays, one per chunk. A chunk stands alone for its id
    range [id_begin, id_end) (lcmtypes/elaslam_global_map_t.lcm): what it does not list
    is no longer in the map and is deleted. Per landmark id (the marker id): ns
    `landmarks`, a sphere coloured by status; ns `ellipses`, its 3-sigma covariance
    ellipse as a flattened cylinder (static landmarks only). A moving landmark has no
    estimate in the map: it is drawn where it was last mapped, without an ellipse, and
    not at all when it was never mapped (as the viewer does)."""

    def __init__(self, maker):
        self.M = maker
        self.shown = set()       # landmark ids with a sphere
        self.ellipses = set()    # landmark ids with an ellipse
        self.last_xy = {}        # landmark id -> its last mapped (x, y) [m]

    def chunk(self, g, header):
        M, d = self.M, LANDMARK_DIAMETER_M
        out, spheres, with_ellipse = [], set(), set()
        for lm in g.landmarks[:max(0, min(g.num_landmarks, len(g.landmarks)))]:
            moving = lm.status == getattr(type(lm), "MOVING", 2)
            self.last_xy[lm.id] = (lm.x, lm.y)
            out.append(M.marker(header, "landmarks", lm.id, M.SPHERE, pose=M.pose2d(lm.x, lm.y, 0.0),
                                scale=M.vec3(d, d, d), color=M.color(MOVING if moving else STATIC)))
            spheres.add(lm.id)
            e = ellipse(lm.cov[0][0], lm.cov[0][1], lm.cov[1][1])
            if e is not None:
                out.append(M.marker(header, "ellipses", lm.id, M.CYLINDER, pose=M.pose2d(lm.x, lm.y, e[2]),
                                    scale=M.vec3(e[0], e[1], ELLIPSE_THICKNESS_M),
                                    color=M.color(MOVING if moving else STATIC, ELLIPSE_ALPHA)))
                with_ellipse.add(lm.id)
        n_moving = max(0, min(g.num_moving, len(g.moving_ids), len(g.moving_by)))
        for lid, by in zip(g.moving_ids[:n_moving], g.moving_by[:n_moving]):
            if lid in spheres or lid not in self.last_xy:
                continue
            x, y = self.last_xy[lid]
            out.append(M.marker(header, "landmarks", lid, M.SPHERE, pose=M.pose2d(x, y, 0.0), scale=M.vec3(d, d, d),
                                color=M.color(MOVING if by > 0 else UNCONFIRMED)))
            spheres.add(lid)
        in_range = lambda i: g.id_begin <= i < g.id_end  # noqa: E731
        out += [M.delete(header, "landmarks", i) for i in sorted(self.shown) if in_range(i) and i not in spheres]
        out += [M.delete(header, "ellipses", i) for i in sorted(self.ellipses) if in_range(i) and i not in with_ellipse]
        self.shown = {i for i in self.shown if not in_range(i)} | spheres
        self.ellipses = {i for i in self.ellipses if not in_range(i)} | with_ellipse
        return M.array(out)
