"""A separate process (one DDS Security identity per process: Cyclone checks permissions per
process, see PROTOCOL.md "Security") that tries, as user CONF, to read the replies of client VICTIM:

    python reply_snoop.py CONF DOMAIN VICTIM_CLIENT_ID

Prints one ``key=value`` line per attempt: ``client`` (a client with the victim's id: the error
class and field, or ``created``), ``reader:<partition>`` (a raw reply reader: ``refused`` or
``allowed``), ``own`` (a reader of the user's own reply partitions, the control) and ``own_client``
(the user's own client: its user and the server's version).
"""

from __future__ import annotations

import sys

from cyclonedds.core import DDSException
from cyclonedds.domain import DomainParticipant
from cyclonedds.qos import Policy, Qos
from cyclonedds.sub import DataReader, Subscriber
from cyclonedds.topic import Topic

import surfeledit
from surfeledit._protocol import TOPIC_REPLY, proto, reply_qos
from surfeledit._protocol import reply_partition
from surfeledit.connection import Client
from surfeledit.security import SecurityConfig, participant_qos


def try_reader(dp: DomainParticipant, topic: Topic, partition: str) -> str:
    try:
        DataReader(Subscriber(dp, qos=Qos(Policy.Partition(partitions=[partition]))), topic, qos=reply_qos())
    except DDSException as e:
        return "refused" if "NOT_ALLOWED_BY_SECURITY" in str(e) else f"error {e}"
    return "allowed"


def main() -> int:
    conf, domain, victim = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    try:
        Client(domain, security=conf, client_id=victim).close()
        print("client=created", flush=True)
    except surfeledit.SurfelEditError as e:
        print(f"client={type(e).__name__}:{e.field}", flush=True)
    config = SecurityConfig.load(conf)
    dp = DomainParticipant(domain, qos=participant_qos(config))
    topic = Topic(dp, TOPIC_REPLY, proto.Reply)
    for partition in (reply_partition(victim), "surfeledit.reply.*", victim.split(".")[0] + ".*", "*"):
        print(f"reader:{partition}={try_reader(dp, topic, partition)}", flush=True)
    print(f"own={try_reader(dp, topic, reply_partition(config.client_id_prefix() + 'x'))}", flush=True)
    dp.__del__()
    with surfeledit.connect(domain, security=config, timeout=15) as own:  # the user's own client is served
        print(f"own_client={own.client_id.split('.')[0]}:{own.info().version}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
