"""CDPR controller node: PD on motor angles + mass feedforward (PDFF, 001 Fig. 6, eq. 14-15).

Each ``/cdpr/joint_states`` sample gives one ``/cdpr/effort_commands`` (motor torques, N m, order
winch_1..n; pre-serialised, naming the stamp of the state it answers for a lock-step simulator)
from :class:`cablelab.plants.cdpr.live.LiveController`: motor-angle PD with the inverse geometric
model of the reference ``/cdpr/reference`` (or a played ``reference_bag``, published there),
feedforward of 001 eq. 14 with the live ``/cdpr/payload_estimate`` (``feedforward`` true, PDFF)
or none (PD), friction compensation (eq. 15) and a minimum-tension floor. A stale or implausible
estimate falls back to the nominal mass (WARN on /diagnostics). Without a reference (or with a
bad motor state) nothing is published (the simulator's brakes hold) and /diagnostics says why.
Matching samples by stamp: :class:`cablelab.plants.cdpr.streams.CommandStream`.

Compiled path (parameter ``compiled_path``, on unless ``CABLELAB_NATIVE=0`` or no compiler): the
references are planned as they come, or in blocks when they come far ahead (:meth:`LiveController.
plan <cablelab.plants.cdpr.live.LiveController.plan>`; each estimate sets the weights of their
feedforward terms, no re-planning), and put in
:class:`~cablelab.plants.cdpr.controller_path.ControllerPath`, whose C thread answers the joint
states with the same law without Python; a state it cannot answer (bad, or no planned row of its
stamp) comes back here and takes the Python path below, which checks and reports it.
Parameters: :data:`.parameters.CONTROLLER` (``pd_feedforward --plant cdpr --help``).
"""
from __future__ import annotations

import math
import time

import numpy as np

from geometry_msgs.msg import InertiaStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import MultiDOFJointTrajectory

from .. import topics
from ..controller_path import ControllerPath
from ..streams import CommandStream, controller_config
from ....ros import fastspin
from ....ros.plant_node import PlantNode
from ....ros.qos import PUBLISHER_DEPTH, publisher_qos, stream_qos
from ....ros.rawmsg import CommandTemplate
from .... import native
from .parameters import CONTROLLER as PARAMETERS


#: the compiled path's rows are planned once the oldest unplanned reference is less than this many
#: reference periods ahead of the newest joint state
PLAN_MARGIN = 4
#: with the compiled path, a reference streamed at least this many periods ahead of the states
#: (:data:`FAR_AHEAD_RUN` times in a row) stops waking the node: the timer takes the references
#: queued since its last run and plans them at once (the rows wait in the library; an estimate
#: only sets the weights of their feedforward)
FAR_AHEAD = 3 * PLAN_MARGIN
#: references in a row that must come :data:`FAR_AHEAD` periods ahead before the node plans them in
#: blocks (0.1 s at 1 kHz: the simulator's steady lead, not a passing burst)
FAR_AHEAD_RUN = 100
#: keep-last depth of the reference subscriptions (this node's and the compiled path's thread's)
REFERENCE_DEPTH = 1000
#: s: the timer's period while states flow (it also waits for late references on the Python path)
TIMER_PERIOD = 0.002
#: s: the longest timer period once references come far ahead (a third of their lead, at least
#: :data:`TIMER_PERIOD`): with the simulator's 50 ms lead the node's Python thread then wakes 60
#: times a second, not 500
BLOCK_PERIOD = 0.02


class CdprController(PlantNode):
    def __init__(self):
        super().__init__("pd_feedforward", start_parameter_services=False)  # smaller wait set
        v = self.v = self.declare_params(PARAMETERS)
        self.stream = CommandStream(v.feedforward, v.sync_wait, v.estimate_wait)
        self.path = None            # the compiled path, once a description configured the law
        self.path_problem = ""      # why there is none (when it was wanted)
        self._path_seen = {"commanded": 0}
        self._native = None
        if v.compiled_path and not v.reference_bag and not self.stream.awaits_estimate:
            self._native = native.load("controller_path")
            if self._native is None:
                self.path_problem = f"compiled path unavailable ({native.unavailable_reason('controller_path')})"
                self.get_logger().info(f"{self.path_problem}: the Python path answers the joint states")
        self.sent = 0
        self._cmd = CommandTemplate("winch")     # pre-serialised commands naming their state's stamp
        self.inputs.add("joint_states", timeout=v.state_timeout)
        self.inputs.add("reference", timeout=v.reference_timeout)
        self.inputs.add("payload_estimate", timeout=v.estimate_timeout, length=1, required=False)
        self.pub_cmd = self.create_publisher(Float64MultiArray, topics.EFFORT_COMMANDS, publisher_qos())
        self.listen_for_description(v.description, keep_first=True)     # it configures the law
        # the reference and the estimate as bytes in deep queues (a busy moment delays samples,
        # drops none); they wake nobody: the reference (published before its state) and the
        # estimate wait queued until a state or the timer takes them (an awaited estimate still
        # wakes the node). The states keep-last 1: after a busy moment the newest state is
        # answered, not a backlog whose commands the simulator would only count as stale
        q = stream_qos(REFERENCE_DEPTH)
        # (with the compiled path the C thread takes the states and each reference wakes this
        # node, which plans its row when due (:meth:`_plan`); the estimate waits for the timer)
        self._unplanned = []
        self._far_ahead = 0         # references in a row streamed far ahead of the states
        self._in_blocks = False     # references taken by the timer, each block planned at once
        self._follow = False        # the compiled path's thread takes the references (in blocks)
        self._handover = False      # ... and this node's subscription still takes them too
        self._overlap_t = None      # stamp of the last sample that subscription took (until passed)
        self._ref_t, self._ref_dt = None, 0.0     # the last reference's stamp, the reference period
        self._ref_sub = self.subscribe(MultiDOFJointTrajectory, topics.REFERENCE, self.on_reference, q, raw=True,
                                       polled=self._native is None)
        self.subscribe(InertiaStamped, topics.PAYLOAD_ESTIMATE, self.on_estimate, q, raw=True,
                       polled=not self.stream.awaits_estimate)
        # the Python path's subscription from the start, also when the compiled path is wanted: the
        # node subscribes to the states before a description configures the law (a launch that
        # waits for this node's subscribers starts the simulator that sends the description);
        # the compiled path's thread replaces it once it runs
        self._state_sub = self.create_subscription(JointState, topics.JOINT_STATES, self.on_state,
                                                   stream_qos(1), raw=True)
        self.player = self.play_reference(v.reference_bag, topics.REFERENCE, ("x", "y", "z"), platform=True)
        self._state_wall = -1.0     # wall time of the last state taken
        self.timer = self.create_timer(TIMER_PERIOD, self.on_timer)
        self.use_fast_executor()
        if self._native is not None:
            self._start_path()          # after the placement: its thread inherits it
        self.start_diagnostics()
        # /diagnostics runs after a command or from the timer, never between a state and its command
        self.defer_timers(t for t in self.timers if t is not self.timer)

    @property
    def controller(self):
        return self.stream.controller

    def set_description(self, desc) -> None:
        self.stream.describe(desc.cdpr, desc.gravity, controller_config(
            self.v, 0.0 if desc.cdpr is None else desc.cdpr.platform_mass))
        if desc.cdpr is not None:
            super().set_description(desc)
            self.inputs.set_length("joint_states", len(desc.cdpr.cables))
            if getattr(self, "_native", None) is not None and self.path is None:
                self._start_path()

    def _start_path(self) -> None:
        """The compiled path for the configured law, its thread answering the joint states (or
        :attr:`path_problem` says why not, and this node takes the states itself)."""
        if self.controller is None or not hasattr(self, "timer"):
            return          # (again once both the description and the placement are here)
        path = ControllerPath(self._native, self.controller, row_wait=self.v.sync_wait)
        problem = path.start(self, topics.JOINT_STATES, topics.EFFORT_COMMANDS, PUBLISHER_DEPTH, self._cmd.label)
        if problem is None:
            self.path = path
            self.destroy_subscription(self._state_sub)
            self._state_sub = None
            self.get_logger().info("compiled path: the joint states are answered by cablelab/csrc/controller_path.c; "
                                   + fastspin.yield_to_compiled(idle=self.python_idle))
            return
        path.close()
        self._native, self.path_problem = None, f"compiled path failed to start ({problem})"
        self.get_logger().warning(f"{self.path_problem}: the Python path answers the joint states")

    def _plan(self, when_due: bool = False) -> None:
        """The rows of the references taken since the last call, planned in one block and put in
        the compiled path (a level platform: a tilted reference is left to the Python path,
        whose prepare handles it). ``when_due``: only once the oldest of them is less than
        :data:`PLAN_MARGIN` reference periods ahead of the newest state the thread took (a
        reference streamed far ahead, as the simulator streams it by default, is planned in
        blocks; one only two periods ahead at once)."""
        if not self._unplanned:
            return
        if when_due and not self._in_blocks:
            dt = self._ref_dt
            newest = self.path.stats()["last_taken"]
            if dt > 0 and math.isfinite(newest):
                ahead = (self._unplanned[-1][-1, 0] - newest) / dt
                self._far_ahead = self._far_ahead + 1 if ahead >= FAR_AHEAD else 0
                if self._far_ahead == FAR_AHEAD_RUN:
                    self._plan_in_blocks(ahead * dt)
                elif self._unplanned[0][0, 0] - newest > PLAN_MARGIN * dt:
                    return
        rows = self._unplanned[0] if len(self._unplanned) == 1 else np.concatenate(self._unplanned)
        self._unplanned = []
        rows = rows[(np.abs(rows[:, 8]) == 1.0) & ~rows[:, 5:8].any(1)]     # quaternion (0, 0, 0, +-1)
        if not len(rows):
            return
        try:
            plan = self.controller.plan(rows[:, 0], rows[:, 2:5], rows[:, 9:12], rows[:, 12:15])
        except (np.linalg.LinAlgError, ValueError, FloatingPointError):
            return          # (no rows: the Python path prepares those stamps and says why)
        self.path.put(plan)

    def _plan_in_blocks(self, lead: float) -> None:
        """References come ``lead`` s ahead of the states: from now on the timer takes them (they
        no longer wake the node), every third of the lead (at most :data:`BLOCK_PERIOD`), and
        plans each block at once. The compiled path's thread then takes them too
        (:meth:`ControllerPath.follow_references <cablelab.plants.cdpr.controller_path.
        ControllerPath.follow_references>`); once its first samples overlap this node's, this
        node's subscription goes (:meth:`_path_references`): no Python take or decode per sample."""
        self._in_blocks = True
        if self._ref_sub not in self.polled:
            fastspin.poll(self, self._ref_sub)
        problem = self.path.follow_references(topics.REFERENCE, REFERENCE_DEPTH)
        if problem is None:
            self._follow = self._handover = True
        else:
            self.get_logger().warning(f"references stay with the Python subscription: {problem}")
        period = min(BLOCK_PERIOD, max(TIMER_PERIOD, lead / 3.0))
        self.destroy_timer(self.timer)
        self.timer = self.create_timer(period, self.on_timer)
        self.get_logger().info(f"references {1000 * lead:.0f} ms ahead: planned in blocks every {1000 * period:.0f} ms")

    def on_reference(self, msg: MultiDOFJointTrajectory) -> None:
        """A reference sample (MultiDOFJointTrajectory or its serialised bytes)."""
        r = self.decode_raw("reference", MultiDOFJointTrajectory, msg)
        if r is not None and self.accept("reference", r["position"]):     # (position None when empty)
            nan = np.full(3, np.nan)
            vel, acc = r["linear_velocity"], r["linear_acceleration"]
            self._references(np.concatenate([(r["t"], 1.0), r["position"], r["quaternion"],
                                             nan if vel is None else vel, nan if acc is None else acc])[None])
            self.command(self.stream.ready())

    def _references(self, rows: np.ndarray) -> None:
        """Good reference samples, (k, :data:`~cablelab.plants.cdpr.controller_path.REF_COLUMNS`)
        rows as :meth:`ControllerPath.references <cablelab.plants.cdpr.controller_path.
        ControllerPath.references>` gives them (NaN: no velocity or acceleration, which the law
        takes as zero): kept for the Python path and, with the compiled path, queued to be
        planned."""
        self.stream.references(rows[:, 0], rows[:, 2:5], rows[:, [8, 5, 6, 7]], rows[:, 9:12], rows[:, 12:15])
        if self.path is not None:
            t = rows[:, 0]
            if len(t) > 1 and t[-1] > t[-2]:
                self._ref_dt = t[-1] - t[-2]       # the reference's period
            elif self._ref_t is not None and t[-1] > self._ref_t:
                self._ref_dt = t[-1] - self._ref_t
            self._ref_t = float(t[-1])
            self._unplanned.append(rows)
            if not self._in_blocks:         # (in blocks: the timer plans what it took)
                self._plan(when_due=True)

    def _path_references(self) -> None:
        """The reference samples the compiled path's thread took since the last call, checked
        (:meth:`InputMonitor.accept_rows <cablelab.ros.inputs.InputMonitor.accept_rows>`: stamp
        and position finite, the position present) and queued as :meth:`on_reference` does. While
        this node's own subscription still takes them (it just took every sample up to
        :attr:`_ref_t`), the thread's are left to it until they reach back to one it took: from
        that overlap on the thread's samples follow without a gap and the subscription goes; the
        thread's samples up to the last one the subscription took (some may come a run later)
        are skipped."""
        rows = self.path.references()
        if not len(rows):
            return
        if self._handover or self._overlap_t is not None:
            last = self._ref_t if self._handover else self._overlap_t
            new = rows[:, 0] > last + 1e-9      # (in stamp order: those taken already come first)
            if self._handover:
                if new.all():
                    return          # no overlap yet: this node's subscription takes these next run
                self._handover = False
                self.polled.remove(self._ref_sub)
                self.destroy_subscription(self._ref_sub)
                self._ref_sub = None
                self.get_logger().info("references taken by the compiled path's thread")
                self._overlap_t = last  # (the thread may still hold samples the subscription took)
            if not new.any():
                return
            rows = rows[int(np.argmax(new)):]
            self._overlap_t = None
        ok = self.inputs.accept_rows("reference", rows[:, [0, 2, 3, 4]], time.monotonic(), rows[:, 1] == 1.0)
        if ok.any():
            self._references(rows[ok])
        self.command(self.stream.ready())

    def on_estimate(self, msg: InertiaStamped) -> None:
        """An estimate (InertiaStamped or its serialised bytes): with the compiled path, its
        weights go to the library at once (every row answered from then on uses them)."""
        est = self.decode_raw("payload_estimate", InertiaStamped, msg)
        if est is None:
            return
        t, m, com = est
        self.stream.estimate(t, m if self.accept("payload_estimate", [m]) else None, com,
                             prepare=self.path is None)
        if self.path is not None:
            self.path.estimate()
        self.command(self.stream.ready())     # a state may have been waiting for this estimate

    def on_state(self, msg: JointState) -> None:
        """A motor state (JointState or its bytes): commanded now if the reference of its stamp is
        here, else a little later (:meth:`on_timer`: DDS does not order samples across topics).
        The queued reference and estimate are taken after the command when the reference terms
        were prepared ahead (:meth:`CommandStream.prepare_next <cablelab.plants.cdpr.streams.
        CommandStream.prepare_next>`), then a due /diagnostics: the state -> command path stays
        short."""
        state = self.decode_raw("joint_states", JointState, msg)
        if state is not None:
            self.take_state(state, time.monotonic())

    def take_state(self, state, now: float) -> None:
        """A decoded motor state received at wall ``now`` (from :meth:`on_state`, or handed over
        by the compiled path)."""
        self._state_wall = now
        if self.player is not None and math.isfinite(state[0]):
            self.player(state[0], ())        # the designed reference of this stamp, published first
        if self.stream.needs_inputs_first(state[0]):
            self.take_polled()          # the reference and estimate that came before it
        self.stream.state(state, now)
        self.command(self.stream.ready())
        self.take_polled()              # then prepare the next stamp's terms, off this path
        self.stream.prepare_next(state[0])
        self.run_deferred()

    def on_timer(self) -> None:
        """A state still waiting for the reference (or the awaited estimate) of its stamp is
        commanded once they came or it waited long enough; while states flow, their own callback
        takes the queued inputs and the timer only runs a due /diagnostics."""
        if self.path is not None:
            self.take_polled()
            if self._follow:
                self._path_references()
            self._plan(when_due=True)
            self._from_path()
        now = time.monotonic()
        if self.stream.pending is not None or (self.path is None and now - self._state_wall > 0.01):
            self.take_polled()
            self.command(self.stream.ready(now))
        self.run_deferred()

    def _from_path(self, handoff: bool = True) -> None:
        """What the compiled path did since the last call: its commands counted as this node's
        (states received, latency, the law's status at the last stamp answered) and (``handoff``)
        the state it handed over taken here."""
        s = self.path.stats()
        new = s["commanded"] - self._path_seen["commanded"]
        if new > 0:
            st = self.inputs.inputs["joint_states"]
            st.received += new
            st.last_time = max(st.last_time or 0.0, s["last_wall"])
            for x in self.path.latencies():
                self.latency.add(float(x))
            if self.controller is not None:
                self.controller.status = self.controller.planned_status(s["last_stamp"])
        self._path_seen = s
        h = self.path.handoff() if handoff else None
        if h is not None:
            t, wall, q, qd = h
            self.take_state((t, None, q, qd, None), wall)

    def command(self, state) -> None:
        """One command for ``state`` = (t, names, position, velocity, effort), if any."""
        if state is None:
            return
        t0 = time.perf_counter()
        if (tau := self.stream.command(state, self.inputs, time.monotonic())) is not None:
            self.pub_cmd.publish(self._cmd.data(tau, state[0]))   # naming the state it answers (lock-step)
            self.sent += 1
            self.latency.since(t0)

    def extend_status(self, level, msg, values):
        if self.path is not None:
            self._from_path(handoff=False)
        path = self._path_seen.get("commanded", 0) if self.path is not None else 0
        level, msg, values = self.stream.report(level, msg, values, "PDFF" if self.v.feedforward else "PD",
                                                self.sent + path)
        if self.path is not None:
            values.update({"compiled path": "on", "commands from the compiled path": str(path),
                           "states handed to Python": str(self._path_seen["handed_off"]),
                           "states waiting for their row": str(self._path_seen["waited"]),
                           "command publishes over 0.2 ms": str(self._path_seen["publish_slow"]),
                           "slowest command publish ms": f"{self._path_seen['publish_max_ms']:.3f}",
                           "references taken by the compiled path": str(self._path_seen["references"])})
            if self._path_seen["references_lost"]:
                values["references lost by the compiled path"] = str(self._path_seen["references_lost"])
        else:
            values["compiled path"] = "off" + (f" ({self.path_problem})" if self.path_problem else "")
        return level, msg, values

    def destroy_node(self):
        if self.path is not None:
            self.path.close()
        return super().destroy_node()


def make_node() -> PlantNode:
    return CdprController()
