"""The Foxglove layout of the view (``docs/foxglove-layout.json``), built with the SDK's
typed layout classes (``foxglove.layouts``), so the file is in the format the app imports.

Left: the 3D panel (fixed frame ``world``, following ``base_link``; its publish tool sends a
pose on ``/goal_pose`` — a new goal in ``papf launch`` sessions). Right, top to bottom:
speed (commanded and measured), charge and power, distance to goal, the log, and the
Parameters panel (the planner's settings). ``papf view --layout FILE`` writes it.
"""

from __future__ import annotations

import json

import foxglove.layouts as fl

GOAL_PUBLISH_TOPIC = "/goal_pose"


def _plot(title: str, *series: tuple[str, str]) -> fl.PlotPanel:
    return fl.PlotPanel(title=title, config=fl.PlotConfig(
        paths=[fl.PlotSeries(value=path, label=label, timestamp_method="receiveTime")
               for path, label in series],
        show_legend=True, legend_display="top"))


def layout() -> fl.Layout:
    """The Foxglove layout of the viewer: 3-D scene, plots of speed, charge and power, logs."""
    three_d = fl.ThreeDeePanel(title="robot", config=fl.ThreeDeeConfig(
        follow_tf="base_link", fixed_frame="world", follow_mode="follow-position",
        publish=fl.ThreeDeePublishSettings(type="pose", pose_topic=GOAL_PUBLISH_TOPIC,
                                           point_topic="/clicked_point"),
        topics={
            "/scan": fl.BaseRendererLaserScanTopicSettings(visible=True, point_size=4,
                                                           color_mode="flat",
                                                           flat_color="#e6194b"),
            "/world": fl.BaseRendererSceneUpdateTopicSettings(visible=True),
            "/planner/scene": fl.BaseRendererSceneUpdateTopicSettings(visible=True),
            "/objects": fl.BaseRendererSceneUpdateTopicSettings(visible=True),
            "/fleet": fl.BaseRendererSceneUpdateTopicSettings(visible=True),
            "/goal": fl.BaseRendererPoseTopicSettings(visible=True),
            "/robot/pose": fl.BaseRendererPoseTopicSettings(visible=False),
        }))
    plots = fl.SplitContainer(direction="column", items=[
        fl.SplitItem(content=_plot("speed [m/s]", ("/cmd_vel.v", "commanded v"),
                                   ("/odom.v", "measured v"))),
        fl.SplitItem(content=_plot("charge [mAh] and power [W]",
                                   ("/battery.charge_used_mAh", "charge used"),
                                   ("/battery.power", "power"))),
        fl.SplitItem(content=_plot("distance to goal [m]",
                                   ("/planner/status.distance_to_goal", "distance"))),
        fl.SplitItem(content=fl.LogPanel(title="events", config=fl.LogConfig(
            topic_to_render="/log", min_log_level=1))),
        fl.SplitItem(content=fl.ParametersPanel(title="planner parameters")),
    ])
    return fl.Layout(content=fl.SplitContainer(direction="row", items=[
        fl.SplitItem(proportion=3, content=three_d),
        fl.SplitItem(proportion=2, content=plots)]))


def layout_json() -> str:
    """The layout as the committed file holds it (indented, newline at the end)."""
    return json.dumps(json.loads(layout().to_json()), indent=2) + "\n"
