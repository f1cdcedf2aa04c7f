// placeholder: messages_ros1 (the bag issue, #32, in progress)
