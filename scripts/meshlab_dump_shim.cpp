// Preloaded into MeshLab 2020.09's meshlabserver by scripts/meshlab_2020_09_tables.py: its filter dump
// (meshlabserver -d) then lists each parameter as a script writes it (<Param name= type= value= .../>,
// with the attributes of its type: min/max, enum values), not by its label.
#include <dlfcn.h>
#include <QDomDocument>
#include <QString>

// RichParameter::fillToXMLDocument(QDomDocument&, bool) const is virtual: call the parameter's own.
typedef QDomElement (*FillToXML)(const void *self, QDomDocument &doc, bool saveDescriptionAndTooltip);

static int fill_slot() {
    static int slot = -2;
    if (slot != -2) return slot;
    slot = -1;
    void *base = dlsym(RTLD_DEFAULT, "_ZNK13RichParameter17fillToXMLDocumentER12QDomDocumentb");
    void **vtable = (void **)dlsym(RTLD_DEFAULT, "_ZTV13RichParameter");
    for (int i = 0; base && vtable && i < 32; ++i)
        if (vtable[2 + i] == base) { slot = i; break; }
    return slot;
}

// RichParameter::fieldDescription() const -> the parameter as a script writes it.
extern "C" const QString *_ZNK13RichParameter16fieldDescriptionEv(const void *self) {
    static QString text;
    int slot = fill_slot();
    if (slot < 0) { text = QString("?"); return &text; }
    FillToXML fill = (FillToXML)((*(void ***)self)[slot]);
    QDomDocument doc;
    QDomElement element = fill(self, doc, false);
    doc.appendChild(element);
    text = doc.toString(-1).trimmed();
    return &text;
}

// ShotfValue::fillToXMLElement asserts in this build: write no value for a camera shot.
extern "C" void _ZNK10ShotfValue16fillToXMLElementER11QDomElement(const void *, QDomElement &) {}
