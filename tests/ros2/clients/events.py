"""Receive collision and text-message topics: drop the ball on the (static) wall, send a text to the moderator."""

from common import Client, emit, todict
from sigcore_msgs import msg

c = Client("events_probe")
c.wait_ready()
hits = c.listen(msg.OnCollisionMsg, "/wall_onCollisionMsg")
texts = c.listen(msg.OnRecvMsg, "/moderator_onRecvMsg")
c.spin(1.0)  # let the subscriptions match
c.publish(msg.EntityVector, "/ball_setPosition", name="", x=3.0, y=0.0, z=1.3)
c.publish(msg.SendMsg, "/bot_sendMsg", to="moderator", content="hello moderator")
c.wait_for(lambda: any(h.name == "ball" for h in hits) and texts, 10.0)
emit({"collisions": [todict(h) for h in hits], "texts": [todict(t) for t in texts]})
