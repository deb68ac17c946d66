"""ROS 2 on the wire: rmw_zenoh's keys, tokens and attachments (:mod:`.wire`), CDR and type hashes (:mod:`.types`)."""
