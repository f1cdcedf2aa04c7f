// placeholder: messages_cdr (the bag issue, #32, in progress)
