"""RecordSelection: which topics of the graph a recording (or a rewrite) keeps.

The options mirror ``ros2 bag record`` (rosbag2): topics and services are chosen separately
(``--topics``/``--all-topics``, ``--services``/``--all-services``), hidden topics (a name part
starting with ``_``) only with ``--include-hidden-topics``, action topics with
``--actions``/``--all-actions`` (the names rosbag2 gave these options after Jazzy). One
difference: ``--all`` here means every topic, not every topic and service as in rosbag2's
``-a``, so that the default bag holds no service-event channel and every reader decodes it
(the official MCAP ROS 2 decoder rejects ``pkg/srv/Name_Event`` types; see
:class:`~icub_pmp.bags.ReaderCheck`).

- A service ``S`` is recorded from its introspection topic ``S/_service_event`` (the server
  must enable introspection; ``/pmp/reach`` does).
- An action ``A`` is recorded from ``A/_action/status`` (``action_msgs/msg/GoalStatusArray``)
  and ``A/_action/feedback`` (``pkg/action/Name_FeedbackMessage``; the MCAP ROS 2 decoder
  rejects that name too). Goals and results travel on the action's hidden services, which
  Jazzy's rclpy cannot introspect.

No ROS import.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from icub_pmp.errors import InvalidInput

__all__ = ["RecordSelection", "SERVICE_EVENT_SUFFIX", "ACTION_TOPICS"]

SERVICE_EVENT_SUFFIX = "/_service_event"
ACTION_TOPICS = ("/_action/feedback", "/_action/status")


def _absolute(name: str) -> str:
    name = name.strip()
    return name if name.startswith("/") else "/" + name


@dataclass(frozen=True)
class RecordSelection:
    """The channels to keep. Names are normalised to absolute ones ('/x')."""

    topics: tuple[str, ...] = ()
    all_topics: bool = False
    services: tuple[str, ...] = ()
    all_services: bool = False
    actions: tuple[str, ...] = ()
    all_actions: bool = False
    include_hidden_topics: bool = False
    exclude: str = ""  # regular expression of topics never kept

    def __post_init__(self) -> None:
        for field in ("topics", "services", "actions"):
            names = getattr(self, field)
            if isinstance(names, str):
                raise InvalidInput(f"{field}: expected a list of names, got the string {names!r}")
            bad = [n for n in names if not isinstance(n, str) or not n.strip()]
            if bad:
                raise InvalidInput(f"{field}: empty or non-string name in {list(names)!r}")
            object.__setattr__(self, field, tuple(_absolute(n) for n in names))
        if self.exclude:
            try:
                re.compile(self.exclude)
            except re.error as exc:
                raise InvalidInput(
                    f"exclude: bad regular expression {self.exclude!r}: {exc}") from None
        if not self.any():
            raise InvalidInput(
                "nothing to record: name topics, or use --all (every topic), --all-services, "
                "--services NAMES, --all-actions or --actions NAMES")

    def any(self) -> bool:
        """Whether anything at all is selected."""
        return bool(self.topics or self.all_topics or self.services or self.all_services
                    or self.actions or self.all_actions)

    # ------------------------------------------------------------------ queries
    def wants(self, topic: str) -> bool:
        """Whether channel ``topic`` is kept."""
        if self.exclude and re.search(self.exclude, topic):
            return False
        if topic in self.topics:
            return True  # named explicitly: whatever it is
        if topic.endswith(SERVICE_EVENT_SUFFIX):
            service = topic[: -len(SERVICE_EVENT_SUFFIX)]
            return self.all_services or service in self.services
        action = _action_of(topic)
        if action is not None:
            return self.all_actions or action in self.actions or (
                self.include_hidden_topics and self.all_topics)
        if _hidden(topic):
            return self.include_hidden_topics and self.all_topics
        return self.all_topics

    def named_topics(self) -> list[str]:
        """The channels asked for by name (topics, service events, action topics), which a
        recorder waits for."""
        out = list(self.topics)
        out += [s + SERVICE_EVENT_SUFFIX for s in self.services]
        out += [a + suffix for a in self.actions for suffix in ACTION_TOPICS]
        return out


def _hidden(topic: str) -> bool:
    return any(part.startswith("_") for part in topic.split("/"))


def _action_of(topic: str) -> str | None:
    for suffix in ACTION_TOPICS:
        if topic.endswith(suffix):
            return topic[: -len(suffix)]
    return None
