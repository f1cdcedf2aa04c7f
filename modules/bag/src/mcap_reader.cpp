// placeholder: mcap_reader (the bag issue, #32, in progress)
