// placeholder: ros1_reader (the bag issue, #32, in progress)
