// placeholder: import_bag (the bag issue, #32, in progress)
